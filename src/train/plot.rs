//! Success curves of a run as a PNG (plotters, headless bitmap backend).

use super::EpochRow;
use anyhow::{anyhow, Context, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// Where the label font is looked for (Debian's fonts-dejavu-core, installed by `make setup`).
pub const FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

fn register_font() -> Result<()> {
    static ONCE: Once = Once::new();
    let mut result = Ok(());
    ONCE.call_once(|| {
        result = std::fs::read(FONT)
            .map_err(|e| anyhow!("cannot read the plot font {FONT} ({e}); install fonts-dejavu-core (make setup)"))
            .and_then(|bytes| {
                // plotters keeps the font for the life of the process.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                    .map_err(|_| anyhow!("{FONT} is not a usable TrueType font"))
            });
    });
    result
}

/// A curve: legend, colour, value of a row.
type Series = (&'static str, RGBColor, fn(&EpochRow) -> f64);

/// Train, test and finals success against the epoch, plus the curriculum level
/// (scaled to [0, 1] by the maximum level), written to `path`.
///
/// # Errors
/// A missing font or an unwritable file.
pub fn success_curves(path: &Path, title: &str, rows: &[EpochRow], max_level: usize) -> Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (900, 540)).into_drawing_area();
    let draw = |e: DrawingAreaErrorKind<_>| anyhow!("drawing {}: {e:?}", path.display());
    root.fill(&WHITE).map_err(draw)?;
    let epochs = rows.last().map_or(1, |r| r.epoch + 1).max(1);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..epochs as f64, 0f64..1.02f64)
        .map_err(draw)?;
    chart.configure_mesh().x_desc("epoch").y_desc("success rate").draw().map_err(draw)?;
    let series: [Series; 4] = [
        ("train", RGBColor(120, 120, 120), |r| r.train_success),
        ("test (current level)", RGBColor(30, 90, 200), |r| r.test_success),
        ("finals (max level)", RGBColor(200, 40, 40), |r| r.finals_success),
        ("level / max", RGBColor(40, 150, 60), |r| r.level as f64),
    ];
    for (i, (name, colour, f)) in series.into_iter().enumerate() {
        let scale = if i == 3 { 1.0 / max_level.max(1) as f64 } else { 1.0 };
        chart
            .draw_series(LineSeries::new(
                rows.iter().map(|r| (r.epoch as f64 + 1.0, f(r) * scale)),
                colour.stroke_width(2),
            ))
            .map_err(draw)?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(draw)?;
    root.present().map_err(draw).with_context(|| format!("writing {}", path.display()))
}
