//! Success curves of a run as a PNG (plotters, headless bitmap backend).

use super::rundir::LogError;
use super::EpochRow;
use crate::support::io::WriteError;
use plotters::prelude::*;
use plotters_backend::DrawingErrorKind;
use plotters_bitmap::BitMapBackendError;
use std::path::{Path, PathBuf};
use std::sync::Once;

/// Where the label font is looked for (Debian's fonts-dejavu-core, installed by `make setup`).
pub const FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// Why a plot could not be drawn or written, or its log read.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The label font could not be read (the OS's error is part of the message).
    #[error("cannot read the plot font {FONT} ({0}); install fonts-dejavu-core (make setup)")]
    NoFont(std::io::Error),
    /// The label font is not one plotters can use.
    #[error("{FONT} is not a usable TrueType font")]
    BadFont,
    /// The output's name does not end in `.png`.
    #[error("{}: plots are PNG images; give a path ending in .png", .0.display())]
    NotPng(PathBuf),
    /// A scaling figure without points.
    #[error("no point to draw: give at least one")]
    NoPoints,
    /// A scaling figure's x that a logarithmic axis cannot hold.
    #[error("x = {0} cannot stand on a logarithmic axis: give x above 0")]
    NotPositive(f64),
    /// plotters could not draw (its error in words: its type is the backend's).
    #[error("{0}")]
    Draw(String),
    /// A plot's drawing or writing failed: what was being done ("drawing", "writing") and to which file.
    #[error("{doing} {}", path.display())]
    At {
        /// "drawing" or "writing".
        doing: &'static str,
        /// The plot.
        path: PathBuf,
        /// What failed.
        #[source]
        source: Box<PlotError>,
    },
    /// The output is refused or its write failed.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// A log to plot could not be read.
    #[error(transparent)]
    Log(#[from] LogError),
}

type Result<T, E = PlotError> = std::result::Result<T, E>;

/// `doing` (drawing, writing) `path` failed with `e`.
fn at<'a>(doing: &'static str, path: &'a Path) -> impl FnOnce(PlotError) -> PlotError + 'a {
    move |e| PlotError::At { doing, path: path.to_owned(), source: Box::new(e) }
}

/// plotters' error drawing `path`, in words (the bitmap backend's own error prints its debug text:
/// an I/O or encoding error is given by its own message instead).
fn drawing(path: &Path) -> impl Fn(DrawingAreaErrorKind<BitMapBackendError>) -> PlotError + Copy + '_ {
    move |e| {
        let words = match &e {
            DrawingAreaErrorKind::BackendError(DrawingErrorKind::DrawingError(b)) => match b {
                BitMapBackendError::IOError(io) => io.to_string(),
                BitMapBackendError::ImageError(image) => image.to_string(),
                other => other.to_string(),
            },
            other => other.to_string(),
        };
        PlotError::Draw(format!("drawing {}: {words}", path.display()))
    }
}

fn register_font() -> Result<()> {
    static ONCE: Once = Once::new();
    let mut result = Ok(());
    ONCE.call_once(|| {
        result = std::fs::read(FONT).map_err(PlotError::NoFont).and_then(|bytes| {
            // plotters keeps the font for the life of the process.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).map_err(|_| PlotError::BadFont)
        });
    });
    result
}

/// A named curve of (x, y) points.
struct Curve {
    label: String,
    colour: RGBColor,
    points: Vec<(f64, f64)>,
    /// Drawn dashed (a reference level, not a run).
    dashed: bool,
}

/// One chart of success-rate curves against `x_desc` on `area`.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    x_desc: &str,
    curves: &[Curve],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let draw = |e: DrawingAreaErrorKind<DB::ErrorType>| PlotError::Draw(format!("drawing: {e}"));
    let x_max = curves.iter().flat_map(|c| c.points.iter().map(|p| p.0)).fold(1e-9, f64::max);
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..x_max, 0f64..1.02f64)
        .map_err(draw)?;
    chart.configure_mesh().x_desc(x_desc).y_desc("success rate").draw().map_err(draw)?;
    for c in curves {
        let colour = c.colour;
        let drawn = if c.dashed {
            chart.draw_series(DashedLineSeries::new(c.points.iter().copied(), 8, 6, colour.stroke_width(2)))
        } else {
            chart.draw_series(LineSeries::new(c.points.iter().copied(), colour.stroke_width(2)))
        };
        drawn.map_err(draw)?.label(c.label.clone()).legend(key(colour.stroke_width(2)));
    }
    legend(&mut chart).map_err(draw)?;
    Ok(())
}

/// A series' mark in a legend: a short line in its style.
fn key(style: ShapeStyle) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style)
}

/// The colours of reference levels (dashed lines across a figure), in order (then again).
const LEVEL_COLOURS: [RGBColor; 2] = [RGBColor(0, 0, 0), RGBColor(150, 150, 150)];

/// The legend box of every chart here: lower right, on a light background.
fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
}

/// Plots are PNG files: another extension is refused before drawing (the
/// encoder would refuse it in its own, unreadable words), and the path is
/// checked as every output is.
///
/// # Errors
/// Another extension, or a path not ours to write.
pub fn png_only(path: &Path) -> Result<()> {
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        return Err(PlotError::NotPng(path.to_owned()));
    }
    crate::support::io::check_output(path)?;
    Ok(())
}

/// Two panels of the same curves: against the epoch (left) and against
/// millions of environment steps (right).
fn two_panels(path: &Path, title: &str, curves: impl Fn(bool) -> Vec<Curve>) -> Result<()> {
    png_only(path)?;
    register_font()?;
    Ok(crate::support::io::write_atomic_via(path, |tmp| two_panels_to(tmp, path, title, curves))?)
}

/// [`two_panels`] drawn into the file `tmp`.
fn two_panels_to(tmp: &Path, path: &Path, title: &str, curves: impl Fn(bool) -> Vec<Curve>) -> Result<()> {
    let root = BitMapBackend::new(tmp, (1400, 540)).into_drawing_area();
    let draw = drawing(path);
    root.fill(&WHITE).map_err(draw)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(draw)?;
    let (left, right) = root.split_horizontally(700);
    panel(&left, "epoch", &curves(false)).map_err(at("drawing", path))?;
    panel(&right, "environment steps (millions)", &curves(true)).map_err(at("drawing", path))?;
    root.present().map_err(draw).map_err(at("writing", path))
}

/// A column of `progress.csv` to draw: legend, colour, value of a row.
type Series = (&'static str, RGBColor, fn(&EpochRow) -> f64);

/// The x value of a row: epochs completed, or millions of env steps.
fn x_of(epoch: usize, env_steps: u64, by_steps: bool) -> f64 {
    if by_steps {
        env_steps as f64 / 1e6
    } else {
        epoch as f64 + 1.0
    }
}

/// Train, test and finals success, plus the curriculum level (scaled to
/// [0, 1] by the maximum level), against the epoch and against env steps,
/// written to `path`.
///
/// # Errors
/// A missing font or an unwritable file.
pub fn success_curves(path: &Path, title: &str, rows: &[EpochRow], max_level: usize) -> Result<()> {
    let series: [Series; 4] = [
        ("train", RGBColor(120, 120, 120), |r| r.train_success),
        ("test (current level)", RGBColor(30, 90, 200), |r| r.test_success),
        ("finals (max level)", RGBColor(200, 40, 40), |r| r.finals_success),
        ("level / max", RGBColor(40, 150, 60), |r| r.level as f64),
    ];
    two_panels(path, title, |by_steps| {
        series
            .iter()
            .enumerate()
            .map(|(i, (name, colour, f))| {
                let scale = if i == 3 { 1.0 / max_level.max(1) as f64 } else { 1.0 };
                Curve {
                    dashed: false,
                    label: (*name).to_owned(),
                    colour: *colour,
                    points: rows.iter().map(|r| (x_of(r.epoch, r.env_steps, by_steps), f(r) * scale)).collect(),
                }
            })
            .collect()
    })
}

/// One evaluation of a run for [`overlay`]: the columns of `progress.csv`
/// that other trainers' logs (e.g. `python -m blockpuzzle.examples.sb3_td3`) have too.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct FinalsPoint {
    pub epoch: usize,
    #[serde(rename = "time/env_steps")]
    pub env_steps: u64,
    #[serde(rename = "finals/success")]
    pub finals_success: f64,
}

impl From<&EpochRow> for FinalsPoint {
    fn from(r: &EpochRow) -> Self {
        Self { epoch: r.epoch, env_steps: r.env_steps, finals_success: r.finals_success }
    }
}

/// Reads the finals curve of a CSV log with `epoch`, `time/env_steps` and
/// `finals/success` columns (others are ignored).
///
/// # Errors
/// A message naming the file for a missing or malformed file.
pub fn read_finals(path: &Path) -> Result<Vec<FinalsPoint>> {
    let rows: Vec<FinalsPoint> =
        super::rundir::read_log(path, "progress log", "CSV with columns epoch, time/env_steps, finals/success")?;
    for r in &rows {
        super::rundir::check_rate(path, r.epoch, "finals/success", r.finals_success)?;
    }
    Ok(rows)
}

/// Finals success of several runs, one curve each, against the epoch and
/// against env steps (the paper's training-plot figure), with `levels` (label, success) drawn as
/// dashed lines across (e.g. the solver's score), written to `path`.
///
/// # Errors
/// A missing font or an unwritable file.
pub fn overlay(path: &Path, title: &str, runs: &[(String, Vec<FinalsPoint>)], levels: &[(String, f64)]) -> Result<()> {
    two_panels(path, title, |by_steps| {
        let curves = runs
            .iter()
            .enumerate()
            .map(|(i, (label, rows))| Curve {
                label: label.clone(),
                colour: COLOURS[i % COLOURS.len()],
                points: rows.iter().map(|r| (x_of(r.epoch, r.env_steps, by_steps), r.finals_success)).collect(),
                dashed: false,
            })
            .collect::<Vec<_>>();
        let x_max = curves.iter().flat_map(|c| c.points.iter().map(|p| p.0)).fold(0.0, f64::max);
        let lines = levels.iter().enumerate().map(|(i, (label, v))| Curve {
            label: label.clone(),
            colour: LEVEL_COLOURS[i % LEVEL_COLOURS.len()],
            points: vec![(0.0, *v), (x_max, *v)],
            dashed: true,
        });
        curves.into_iter().chain(lines).collect()
    })
}

/// One evaluated policy of a [`evaluated`] curve: the env steps its training had taken, its test
/// success, and the 95% Wilson interval where there is one (a test split of one row).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvalPoint {
    pub env_steps: u64,
    pub success: f64,
    pub ci95: Option<(f64, f64)>,
}

/// The colours of a figure's curves, in order (then again).
const COLOURS: [RGBColor; 10] = [
    RGBColor(200, 40, 40),
    RGBColor(30, 90, 200),
    RGBColor(40, 150, 60),
    RGBColor(230, 140, 20),
    RGBColor(130, 60, 170),
    RGBColor(90, 90, 90),
    RGBColor(0, 160, 170),
    RGBColor(140, 90, 40),
    RGBColor(230, 90, 170),
    RGBColor(150, 160, 30),
];

/// Test success of evaluated policies (`eval --suite` results, e.g. a run's snapshots) against
/// the env steps each had trained for: one curve per label, a marker and its 95% interval per
/// policy, and `levels` (label, success) drawn as dashed lines across (e.g. the solver's), written
/// to `path`.
///
/// # Errors
/// No point, a missing font or an unwritable file.
pub fn evaluated(
    path: &Path,
    title: &str,
    curves: &[(String, Vec<EvalPoint>)],
    levels: &[(String, f64)],
) -> Result<()> {
    png_only(path)?;
    if curves.iter().all(|(_, p)| p.is_empty()) {
        return Err(PlotError::NoPoints);
    }
    register_font()?;
    Ok(crate::support::io::write_atomic_via(path, |tmp| {
        let root = BitMapBackend::new(tmp, (1000, 600)).into_drawing_area();
        let draw = drawing(path);
        root.fill(&WHITE).map_err(draw)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(draw)?;
        let x = |p: &EvalPoint| p.env_steps as f64 / 1e3;
        let x_max = curves.iter().flat_map(|(_, p)| p.iter().map(x)).fold(1e-9, f64::max) * 1.05;
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(54)
            .build_cartesian_2d(0f64..x_max, 0f64..1.02f64)
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc("environment steps (thousands)")
            .y_desc("test success (95% Wilson interval)")
            .draw()
            .map_err(draw)?;
        for (i, (label, points)) in curves.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            chart
                .draw_series(LineSeries::new(points.iter().map(|p| (x(p), p.success)), colour.stroke_width(2)))
                .map_err(draw)?
                .label(label.clone())
                .legend(key(colour.stroke_width(2)));
            chart
                .draw_series(points.iter().map(|p| Circle::new((x(p), p.success), 4, colour.filled())))
                .map_err(draw)?;
            let bars = points.iter().filter_map(|p| {
                p.ci95.map(|(lo, hi)| ErrorBar::new_vertical(x(p), lo, p.success, hi, colour.stroke_width(1), 8))
            });
            chart.draw_series(bars).map_err(draw)?;
        }
        for (i, (label, v)) in levels.iter().enumerate() {
            let colour = LEVEL_COLOURS[i % LEVEL_COLOURS.len()];
            chart
                .draw_series(DashedLineSeries::new([(0.0, *v), (x_max, *v)], 8, 6, colour.stroke_width(2)))
                .map_err(draw)?
                .label(label.clone())
                .legend(key(colour.stroke_width(2)));
        }
        legend(&mut chart).map_err(draw)?;
        root.present().map_err(draw).map_err(at("writing", path))
    })?)
}

/// Smallest distance the deviation plot shows: exact agreement (0) is drawn here.
const DEVIATION_FLOOR: f64 = 1e-12;

/// The alignment check's figure (`blockpuzzle align --plot`): per step, the
/// distance between the reference and the replayed gripper (left) and block
/// (right) positions, one line per episode, on a log scale with the 1e-4 m
/// tolerance marked; exact agreement is drawn at 1e-12 m.
///
/// # Errors
/// A missing font or an unwritable file.
pub fn deviations(path: &Path, title: &str, episodes: &[(String, Vec<[f64; 2]>)], tolerance: f64) -> Result<()> {
    png_only(path)?;
    register_font()?;
    Ok(crate::support::io::write_atomic_via(path, |tmp| {
        let root = BitMapBackend::new(tmp, (1400, 540)).into_drawing_area();
        let draw = drawing(path);
        root.fill(&WHITE).map_err(draw)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(draw)?;
        let (left, right) = root.split_horizontally(700);
        let steps = episodes.iter().map(|(_, d)| d.len()).max().unwrap_or(1).max(2) as f64 - 1.0;
        for (area, which, name) in [(&left, 0, "gripper"), (&right, 1, "block")] {
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .caption(name, ("sans-serif", 18))
                .build_cartesian_2d(0f64..steps, (DEVIATION_FLOOR..1f64).log_scale())
                .map_err(draw)?;
            chart
                .configure_mesh()
                .x_desc("step")
                .y_desc("distance (m)")
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .draw()
                .map_err(draw)?;
            let tol = RGBColor(90, 90, 90);
            chart
                .draw_series(LineSeries::new([(0.0, tolerance), (steps, tolerance)], tol.stroke_width(1)))
                .map_err(draw)?
                .label(format!("tolerance {tolerance:.0e} m"))
                .legend(key(tol.stroke_width(1)));
            for (i, (label, d)) in episodes.iter().enumerate() {
                let colour = Palette99::pick(i).to_rgba();
                let points = d.iter().enumerate().map(|(t, v)| (t as f64, v[which].max(DEVIATION_FLOOR)));
                chart
                    .draw_series(LineSeries::new(points, colour.stroke_width(2)))
                    .map_err(draw)?
                    .label(label.clone())
                    .legend(key(colour.stroke_width(2)));
            }
            legend(&mut chart).map_err(draw)?;
        }
        root.present().map_err(draw).map_err(at("writing", path))
    })?)
}

/// One point of a scaling figure: the x value (e.g. the number of distinct training tasks) and the
/// train and test splits' mean success of one result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalingPoint {
    pub x: f64,
    pub train: f64,
    pub test: f64,
}

/// Train and test success against `x_desc` on a base-2 logarithmic axis (the Procgen curve): every
/// point as a marker, a line through the mean at each x, and `reference` (train, test) drawn as
/// dashed horizontal lines (e.g. the solver's), written to `path`.
///
/// # Errors
/// No point, an x not above 0, a missing font or an unwritable file.
pub fn scaling(
    path: &Path,
    title: &str,
    x_desc: &str,
    points: &[ScalingPoint],
    reference: Option<(&str, f64, f64)>,
) -> Result<()> {
    png_only(path)?;
    if points.is_empty() {
        return Err(PlotError::NoPoints);
    }
    if let Some(p) = points.iter().find(|p| !(p.x > 0.0 && p.x.is_finite())) {
        return Err(PlotError::NotPositive(p.x));
    }
    register_font()?;
    Ok(crate::support::io::write_atomic_via(path, |tmp| {
        let root = BitMapBackend::new(tmp, (900, 560)).into_drawing_area();
        let draw = drawing(path);
        root.fill(&WHITE).map_err(draw)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(draw)?;
        let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(54)
            .build_cartesian_2d((lo / 1.5..hi * 1.5).log_scale().base(2.0), 0f64..1.02f64)
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("success rate")
            .x_label_formatter(&|x| format!("{x:.0}"))
            .draw()
            .map_err(draw)?;
        let mut xs: Vec<f64> = points.iter().map(|p| p.x).collect();
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        type Series<'a> = (&'a str, RGBColor, fn(&ScalingPoint) -> f64);
        let series: [Series; 2] =
            [("train split", RGBColor(30, 90, 200), |p| p.train), ("test split", RGBColor(200, 40, 40), |p| p.test)];
        for (label, colour, of) in series {
            let means: Vec<(f64, f64)> = xs
                .iter()
                .map(|&x| {
                    let at: Vec<f64> = points.iter().filter(|p| p.x == x).map(of).collect();
                    (x, at.iter().sum::<f64>() / at.len() as f64)
                })
                .collect();
            chart
                .draw_series(LineSeries::new(means, colour.stroke_width(2)))
                .map_err(draw)?
                .label(format!("{label} (mean over seeds)"))
                .legend(key(colour.stroke_width(2)));
            chart.draw_series(points.iter().map(|p| Circle::new((p.x, of(p)), 4, colour.filled()))).map_err(draw)?;
        }
        if let Some((name, train, test)) = reference {
            for (value, colour, which) in
                [(train, RGBColor(30, 90, 200), "train"), (test, RGBColor(200, 40, 40), "test")]
            {
                let dashes = DashedLineSeries::new(
                    [(lo / 1.5, value), (hi * 1.5, value)],
                    8,
                    6,
                    colour.mix(0.6).stroke_width(1),
                );
                chart
                    .draw_series(dashes)
                    .map_err(draw)?
                    .label(format!("{name}, {which}"))
                    .legend(key(colour.mix(0.6).stroke_width(1)));
            }
        }
        legend(&mut chart).map_err(draw)?;
        root.present().map_err(draw).map_err(at("writing", path))
    })?)
}
