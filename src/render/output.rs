//! Writing rendered frames: an animated GIF, a folder of PNGs, or a
//! filmstrip PNG of evenly spaced frames side by side. Files are written
//! to a temporary name and renamed, so a failure leaves nothing behind.

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbImage, RgbaImage};
use std::path::{Path, PathBuf};

/// Why frames could not be written, naming the output.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Nothing to write.
    #[error("no frames to write to {}", path.display())]
    NoFrames {
        /// The output.
        path: PathBuf,
    },
    /// A filmstrip of more frames than the episode has.
    #[error("the episode has {frames} frames, --filmstrip {asked} asks for more; give --filmstrip {frames} or less")]
    TooFewFrames {
        /// The episode's frames.
        frames: usize,
        /// The frames asked for.
        asked: usize,
    },
    /// A file (GIF, filmstrip) that cannot be encoded or written.
    #[error(transparent)]
    Write(#[from] crate::support::io::WriteError),
    /// The staging folder of a folder of PNGs cannot be made.
    #[error("cannot write {}", path.display())]
    Folder {
        /// The folder.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A frame of a folder of PNGs cannot be encoded or written.
    #[error("cannot write {}", path.display())]
    Frame {
        /// The frame's file.
        path: PathBuf,
        /// Why.
        #[source]
        source: image::ImageError,
    },
    /// A staged frame cannot be moved into an existing folder.
    #[error("cannot move {name} into {}", dir.display())]
    MoveInto {
        /// The frame's file name.
        name: String,
        /// The folder.
        dir: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The staged folder cannot be moved into place.
    #[error("cannot move {} to {}", from.display(), to.display())]
    Move {
        /// The staged folder.
        from: PathBuf,
        /// The folder.
        to: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

/// A library's error while writing a temporary file.
type Boxed = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Writes `frames` as an animated GIF at `fps`, looping.
///
/// # Errors
/// No frames, I/O or encoding errors.
pub fn gif(path: &Path, frames: &[RgbImage], fps: u32) -> Result<(), OutputError> {
    if frames.is_empty() {
        return Err(OutputError::NoFrames { path: path.to_owned() });
    }
    atomic(path, |tmp| -> Result<(), Boxed> {
        let file = std::fs::File::create(tmp)?;
        let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
        enc.set_repeat(Repeat::Infinite)?;
        let delay = Delay::from_numer_denom_ms(1000, fps.max(1));
        for f in frames {
            let rgba: RgbaImage = image::DynamicImage::ImageRgb8(f.clone()).to_rgba8();
            enc.encode_frame(Frame::from_parts(rgba, 0, 0, delay))?;
        }
        Ok(())
    })
}

/// Writes `frames` as `frame_00000.png`, ... into the folder `dir` (created):
/// all of them into a temporary folder beside it first, then moved into place
/// (renames, which need no space), so a failure leaves no frames behind.
///
/// # Errors
/// I/O or encoding errors, naming the folder.
pub fn png_folder(dir: &Path, frames: &[RgbImage]) -> Result<(), OutputError> {
    let tmp = crate::support::io::temp_path(dir);
    let staged = crate::support::io::CreatedDir::create(&tmp)
        .map_err(|source| OutputError::Folder { path: dir.to_owned(), source })?;
    let names: Vec<String> = (0..frames.len()).map(|k| format!("frame_{k:05}.png")).collect();
    for (f, name) in frames.iter().zip(&names) {
        f.save_with_format(tmp.join(name), image::ImageFormat::Png)
            .map_err(|source| OutputError::Frame { path: dir.join(name), source })?;
    }
    if dir.exists() {
        for name in &names {
            std::fs::rename(tmp.join(name), dir.join(name)).map_err(|source| OutputError::MoveInto {
                name: name.clone(),
                dir: dir.to_owned(),
                source,
            })?;
        }
    } else {
        std::fs::rename(&tmp, dir).map_err(|source| OutputError::Move {
            from: tmp.clone(),
            to: dir.to_owned(),
            source,
        })?;
    }
    drop(staged);
    Ok(())
}

/// The indices of `n` evenly spaced frames out of `len`, first and last included.
pub fn filmstrip_indices(len: usize, n: usize) -> Vec<usize> {
    match (len, n) {
        (0, _) | (_, 0) => vec![],
        (_, 1) => vec![len - 1],
        _ => (0..n.min(len)).map(|k| k * (len - 1) / (n.min(len) - 1)).collect(),
    }
}

/// Writes `n` evenly spaced frames of `frames` side by side as one PNG.
///
/// # Errors
/// No frames, I/O or encoding errors.
pub fn filmstrip(path: &Path, frames: &[RgbImage], n: usize) -> Result<(), OutputError> {
    if n > frames.len() && !frames.is_empty() {
        return Err(OutputError::TooFewFrames { frames: frames.len(), asked: n });
    }
    let picks = filmstrip_indices(frames.len(), n);
    let Some(first) = picks.first().map(|&k| &frames[k]) else {
        return Err(OutputError::NoFrames { path: path.to_owned() });
    };
    let (w, h) = first.dimensions();
    let mut strip = RgbImage::new(w * picks.len() as u32, h);
    for (slot, &k) in picks.iter().enumerate() {
        image::imageops::replace(&mut strip, &frames[k], (slot as u32 * w) as i64, 0);
    }
    atomic(path, |tmp| strip.save_with_format(tmp, image::ImageFormat::Png))
}

fn atomic<E: Into<Boxed>>(path: &Path, write: impl FnOnce(&Path) -> Result<(), E>) -> Result<(), OutputError> {
    Ok(crate::support::io::write_atomic_via(path, write)?)
}

#[cfg(test)]
mod tests {
    use super::filmstrip_indices;

    #[test]
    fn filmstrip_frames_are_evenly_spaced_with_both_ends() {
        assert_eq!(filmstrip_indices(51, 5), vec![0, 12, 25, 37, 50]);
        assert_eq!(filmstrip_indices(3, 5), vec![0, 1, 2]);
        assert_eq!(filmstrip_indices(10, 1), vec![9]);
        assert!(filmstrip_indices(0, 4).is_empty());
    }
}
