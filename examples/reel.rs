//! The README's opening picture: animated GIFs of the gallery side by side, frame by frame, in one
//! animated GIF (a shorter one holds its last frame until the longest ends). scripts/gallery.sh
//! makes it from the GIFs it renders.
//! Usage: cargo run --release --example reel -- OUT.gif FPS A.gif B.gif ...
use anyhow::{bail, Context, Result};
use image::{AnimationDecoder, RgbImage};

fn frames(path: &str) -> Result<Vec<RgbImage>> {
    let file = std::io::BufReader::new(std::fs::File::open(path).with_context(|| format!("opening {path}"))?);
    let decoder = image::codecs::gif::GifDecoder::new(file).with_context(|| format!("{path} is no GIF"))?;
    let frames = decoder.into_frames().collect_frames().with_context(|| format!("decoding {path}"))?;
    Ok(frames.into_iter().map(|f| image::DynamicImage::ImageRgba8(f.into_buffer()).to_rgb8()).collect())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, fps, inputs @ ..] = args.as_slice() else { bail!("usage: reel OUT.gif FPS A.gif B.gif ...") };
    if inputs.is_empty() {
        bail!("give at least one GIF to put in the reel");
    }
    let fps: u32 = fps.parse().context("FPS is a whole number of frames per second")?;
    let clips = inputs.iter().map(|p| frames(p)).collect::<Result<Vec<_>>>()?;
    let (w, h) = (clips[0][0].width(), clips[0][0].height());
    if clips.iter().any(|c| c.is_empty() || c[0].dimensions() != (w, h)) {
        bail!("the GIFs differ in size (or one is empty): give frames of one size, as scripts/gallery.sh renders them");
    }
    let longest = clips.iter().map(Vec::len).max().unwrap_or(0);
    let reel: Vec<RgbImage> = (0..longest)
        .map(|k| {
            let mut tile = RgbImage::new(w * clips.len() as u32, h);
            for (i, clip) in clips.iter().enumerate() {
                let frame = &clip[k.min(clip.len() - 1)];
                image::imageops::replace(&mut tile, frame, (i as u32 * w) as i64, 0);
            }
            tile
        })
        .collect();
    blockpuzzle::render::output::gif(std::path::Path::new(out), &reel, fps)?;
    println!("wrote {out}: {} frames of {} clips", reel.len(), clips.len());
    Ok(())
}
