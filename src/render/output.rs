//! Writing rendered frames: an animated GIF, a folder of PNGs, or a
//! filmstrip PNG of evenly spaced frames side by side. Files are written
//! to a temporary name and renamed, so a failure leaves nothing behind.

use anyhow::{bail, Context, Result};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, RgbImage, RgbaImage};
use std::path::Path;

/// Writes `frames` as an animated GIF at `fps`, looping.
///
/// # Errors
/// No frames, I/O or encoding errors.
pub fn gif(path: &Path, frames: &[RgbImage], fps: u32) -> Result<()> {
    if frames.is_empty() {
        bail!("no frames to write to {}", path.display());
    }
    atomic(path, |tmp| {
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
pub fn png_folder(dir: &Path, frames: &[RgbImage]) -> Result<()> {
    let tmp = crate::support::io::temp_path(dir);
    let staged =
        crate::support::io::CreatedDir::create(&tmp).with_context(|| format!("cannot write {}", dir.display()))?;
    let names: Vec<String> = (0..frames.len()).map(|k| format!("frame_{k:05}.png")).collect();
    for (f, name) in frames.iter().zip(&names) {
        f.save_with_format(tmp.join(name), image::ImageFormat::Png)
            .with_context(|| format!("cannot write {}", dir.join(name).display()))?;
    }
    if dir.exists() {
        for name in &names {
            std::fs::rename(tmp.join(name), dir.join(name))
                .with_context(|| format!("cannot move {} into {}", name, dir.display()))?;
        }
    } else {
        std::fs::rename(&tmp, dir).with_context(|| format!("cannot move {} to {}", tmp.display(), dir.display()))?;
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
pub fn filmstrip(path: &Path, frames: &[RgbImage], n: usize) -> Result<()> {
    if n > frames.len() && !frames.is_empty() {
        bail!(
            "the episode has {} frames, --filmstrip {n} asks for more; give --filmstrip {} or less",
            frames.len(),
            frames.len()
        );
    }
    let picks = filmstrip_indices(frames.len(), n);
    let Some(first) = picks.first().map(|&k| &frames[k]) else {
        bail!("no frames to write to {}", path.display());
    };
    let (w, h) = first.dimensions();
    let mut strip = RgbImage::new(w * picks.len() as u32, h);
    for (slot, &k) in picks.iter().enumerate() {
        image::imageops::replace(&mut strip, &frames[k], (slot as u32 * w) as i64, 0);
    }
    atomic(path, |tmp| Ok(strip.save_with_format(tmp, image::ImageFormat::Png)?))
}

fn atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
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
