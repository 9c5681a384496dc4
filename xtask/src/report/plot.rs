//! The report's PNG plots, drawn with plotters.
//!
//! - [`pareto`]: error against the converged reference versus real-time factor for one case, for
//!   the contact force and for the output signal (one panel when the two are the same signal, as on
//!   the mass–barrier), every configuration as a light marker (colour = method) and each method's
//!   Pareto front as a line with solid markers (the configurations no other configuration of that
//!   method beats in both error and run time), labelled `N·k×` (QSA: segments · oversampling) or
//!   `k×` (EXP, IMP: oversampling); a label that would overlap one already drawn is left out. The
//!   dashed line is the 1 % goal (−2), the dotted line the reference's own error (below it, errors
//!   are unresolved). The legend explains all of these.
//! - [`fig5_right`]: the seed's Fig. 5 (right) measure, the force error against IMP at the same
//!   rate, versus `log10(Δy/y_ref) = −log10 N`, at the base rate, one curve per case.
//! - [`trajectories`]: the Fig. 4 study ([`super::fig4`]), one panel per scheme, one colour per
//!   entry phase (the legend in the first panel).
//!
//! Each PNG is drawn into a temporary file in the report directory and renamed into place.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use qsa_dsp::contact::Method;

use super::ReportError;
use super::analysis::Signal;
use super::error::ErrorRow;
use super::fig4::Fig4Study;
use super::files::make_readable;
use super::pareto::front;

/// Size of the single-panel plots (pixels).
const SIZE: (u32, u32) = (960, 640);

const QSA_COLOUR: RGBColor = RGBColor(31, 119, 180);
const EXP_COLOUR: RGBColor = RGBColor(214, 39, 40);
const IMP_COLOUR: RGBColor = RGBColor(20, 20, 20);

/// Colour of a method's markers and front.
pub fn colour(method: Method) -> RGBColor {
    match method {
        Method::Qsa => QSA_COLOUR,
        Method::Exp => EXP_COLOUR,
        Method::Imp => IMP_COLOUR,
    }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Draw into `path` (a PNG) through a temporary file beside it.
fn draw_png(path: &Path, size: (u32, u32), draw: impl FnOnce(&Area) -> Result<(), String>) -> Result<(), ReportError> {
    let fail = |message: String| ReportError::Plot { path: path.to_owned(), message };
    let dir = path.parent().unwrap_or(Path::new("."));
    let temp = tempfile::Builder::new()
        .prefix(".plot-")
        .suffix(".png")
        .tempfile_in(dir)
        .map_err(|e| ReportError::Io { path: dir.to_owned(), source: e })?;
    {
        let root = BitMapBackend::new(temp.path(), size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
        draw(&root).map_err(fail)?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    make_readable(temp.as_file()).map_err(|e| ReportError::Io { path: path.to_owned(), source: e })?;
    temp.persist(path).map_err(|e| ReportError::Io { path: path.to_owned(), source: e.error })?;
    Ok(())
}

/// `(lo, hi)` of the finite values, padded by `pad` of the span (at least `min_span`).
fn range(values: impl Iterator<Item = f64>, pad: f64, min_span: f64) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = (hi - lo).max(min_span);
    (lo - pad * span, hi + pad * span)
}

fn short_label(row: &ErrorRow) -> String {
    match row.config.method {
        Method::Qsa => format!("{}·{}×", row.config.segments, row.config.oversampling),
        _ => format!("{}×", row.config.oversampling),
    }
}

/// A tick label for a logarithmic axis: `1e-2`, `2e-2`, `5e-2`; the ticks in between stay
/// unlabelled so the labels never run into each other.
fn log_tick(x: &f64) -> String {
    if is_labelled_log_tick(*x) { format!("{x:.0e}") } else { String::new() }
}

/// Whether a tick of a logarithmic axis gets a label: 1, 2 and 5 times a power of ten.
pub fn is_labelled_log_tick(x: f64) -> bool {
    let mantissa = x / 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0].iter().any(|m| (mantissa - m).abs() < 1e-6 * m) || (mantissa - 10.0).abs() < 1e-5
}

/// Error against the reference versus RTF for one case: the contact force (left) and the output
/// signal (right), or the force alone when every row's output error equals its force error.
/// `check` is the reference's own `(force, output)` error.
pub fn pareto(path: &Path, title: &str, rows: &[&ErrorRow], check: (f64, f64)) -> Result<(), ReportError> {
    let same = rows.iter().all(|r| r.output_error_vs_reference == r.error_vs_reference);
    let width = if same { 900 } else { 1500 };
    draw_png(path, (width, 640), |root| {
        let root = root.titled(title, ("sans-serif", 26)).map_err(|e| e.to_string())?;
        if same {
            return pareto_panel(&root, rows, Signal::Force, check.0, "force (= output) signal");
        }
        let (left, right) = root.split_horizontally(750);
        pareto_panel(&left, rows, Signal::Force, check.0, "force signal")?;
        pareto_panel(&right, rows, Signal::Output, check.1, "output signal")
    })
}

fn pareto_panel(area: &Area, rows: &[&ErrorRow], signal: Signal, check: f64, caption: &str) -> Result<(), String> {
    let timed: Vec<&ErrorRow> =
        rows.iter().copied().filter(|r| r.rtf.is_some_and(|t| t > 0.0) && signal.of(r).is_finite()).collect();
    let (x0, x1) = range(timed.iter().map(|r| r.rtf.unwrap_or(1.0).log10()), 0.05, 0.5);
    let (y0, y1) =
        range(timed.iter().map(|r| signal.of(r)).chain([-2.0]).chain(Some(check).filter(|c| c.is_finite())), 0.08, 1.0);
    // Room below the data for the legend (lower left): a third of the height.
    let y0 = y0 - 0.45 * (y1 - y0);
    let (x0, x1) = (10f64.powf(x0), 10f64.powf(x1));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("real-time factor (wall s per simulated s)")
        .y_desc(format!("log10 {} error vs converged reference", signal.name()))
        .x_label_formatter(&log_tick)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| e.to_string())?;
    let grey = BLACK.mix(0.5).stroke_width(1);
    chart
        .draw_series(DashedLineSeries::new([(x0, -2.0), (x1, -2.0)], 8, 6, grey))
        .map_err(|e| e.to_string())?
        .label("1 % of the reference (−2)")
        .legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (8, 0)], grey)
                + PathElement::new(vec![(14, 0), (20, 0)], grey)
        });
    if check > y0 && check < y1 {
        chart
            .draw_series(DashedLineSeries::new([(x0, check), (x1, check)], 2, 4, BLACK.stroke_width(1)))
            .map_err(|e| e.to_string())?
            .label("reference's own error (below: unresolved)")
            .legend(|(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (2, 0)], BLACK)
                    + PathElement::new(vec![(6, 0), (8, 0)], BLACK)
                    + PathElement::new(vec![(12, 0), (14, 0)], BLACK)
                    + PathElement::new(vec![(18, 0), (20, 0)], BLACK)
            });
    }
    let mut placed: Vec<(i32, i32)> = Vec::new();
    for method in [Method::Qsa, Method::Exp, Method::Imp] {
        let c = colour(method);
        let points: Vec<(f64, f64, String)> = timed
            .iter()
            .filter(|r| r.config.method == method)
            .map(|r| (r.rtf.unwrap_or(f64::NAN), signal.of(r), short_label(r)))
            .collect();
        let marker_style = c.mix(0.45).filled();
        chart
            .draw_series(points.iter().map(|p| Circle::new((p.0, p.1), 4, marker_style)))
            .map_err(|e| e.to_string())?;
        // The front ranks the rows as the tables do: an error below the reference's own counts as
        // that (unresolved), so the line runs along it there while the dots stay where they fell,
        // and a dearer row joins only when better by more than the report's tolerance.
        let capped: Vec<(f64, f64, String)> = points.iter().map(|p| (p.0, p.1.max(check), p.2.clone())).collect();
        let best = front(&capped, super::analysis::ERROR_TOLERANCE);
        chart
            .draw_series(LineSeries::new(best.iter().map(|p| (p.0, p.1)), c.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(format!("{}: front (line), every configuration (light dots)", method.name().to_uppercase()))
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (14, 0)], c.stroke_width(2))
                    + Circle::new((7, 0), 5, c.filled())
                    + Circle::new((19, 0), 4, marker_style)
            });
        chart.draw_series(best.iter().map(|p| Circle::new((p.0, p.1), 5, c.filled()))).map_err(|e| e.to_string())?;
        let mut labels = Vec::new();
        for p in &best {
            let (px, py) = chart.backend_coord(&(p.0, p.1));
            let (lx, ly) = (px + 6, py - 16);
            let width = 7 * p.2.chars().count() as i32;
            if placed.iter().any(|&(x, y)| (lx - x).abs() < width.max(40) && (ly - y).abs() < 14) {
                continue;
            }
            placed.push((lx, ly));
            labels.push(p.clone());
        }
        chart
            .draw_series(labels.iter().map(|p| {
                EmptyElement::at((p.0, p.1))
                    + Text::new(p.2.clone(), (6, -16), ("sans-serif", 13).into_font().color(&c))
            }))
            .map_err(|e| e.to_string())?;
    }
    chart
        .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
        .map_err(|e| e.to_string())?
        .label("labels: N·k× = QSA with N segments at k× the base rate; k× = EXP or IMP at k×")
        .legend(|(x, y)| EmptyElement::at((x, y)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// Force error against IMP at the base rate versus `log10(Δy/y_ref)`, one curve per case.
pub fn fig5_right(path: &Path, curves: &[(String, Vec<(f64, f64)>)]) -> Result<(), ReportError> {
    let (x0, x1) = range(curves.iter().flat_map(|c| c.1.iter().map(|p| p.0)), 0.04, 1.0);
    let (y0, y1) = range(curves.iter().flat_map(|c| c.1.iter().map(|p| p.1)), 0.06, 1.0);
    draw_png(path, SIZE, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("QSA force error against IMP at the base rate (seed Fig. 5, right)", ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("log10(Δy / y_ref) = −log10 N")
            .y_desc("log10 ‖F_QSA − F_IMP‖ / ‖F_IMP‖")
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, (name, points)) in curves.iter().enumerate() {
            let c = Palette99::pick(i).to_rgba();
            let width = if name.starts_with("fig5") { 4 } else { 2 };
            chart
                .draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(width)))
                .map_err(|e| e.to_string())?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(width)));
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, c.filled()))).map_err(|e| e.to_string())?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}

/// The Fig. 4 study: one panel per scheme, compression against time since the free-flight entry.
pub fn trajectories(path: &Path, study: &Fig4Study) -> Result<(), ReportError> {
    let longest = study.schemes.iter().map(|s| s.contact_samples.1).fold(0.0, f64::max);
    let (x0, x1) = (-2.0, longest + 3.0);
    let in_window = |p: &&(f64, f64)| p.0 >= x0 && p.0 <= x1;
    let (y0, y1) = range(
        study.schemes.iter().flat_map(|s| s.curves.iter().flat_map(|c| c.iter().filter(in_window).map(|p| p.1))),
        0.05,
        1.0,
    );
    let columns = study.schemes.len().div_ceil(2);
    draw_png(path, (560 * columns as u32, 880), |root| {
        let panels = root.split_evenly((2, columns));
        for (index, (panel, scheme)) in panels.iter().zip(&study.schemes).enumerate() {
            let title = format!(
                "{}: contact {:.3}–{:.3} samples",
                scheme.label, scheme.contact_samples.0, scheme.contact_samples.1
            );
            let mut chart = ChartBuilder::on(panel)
                .caption(title, ("sans-serif", 19))
                .margin(10)
                .x_label_area_size(42)
                .y_label_area_size(56)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc("(t − t_in)/Δt (samples since the free-flight entry)")
                .y_desc("compression y (µm)")
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 15))
                .draw()
                .map_err(|e| e.to_string())?;
            let phases = scheme.curves.len();
            for (i, curve) in scheme.curves.iter().enumerate() {
                let c = Palette99::pick(i).to_rgba();
                let points: Vec<(f64, f64)> = curve.iter().filter(in_window).copied().collect();
                let series = chart
                    .draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(1)))
                    .map_err(|e| e.to_string())?;
                if index == 0 {
                    series
                        .label(format!("entry phase {i}/{phases} of a sample"))
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
                }
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, c.filled()))).map_err(|e| e.to_string())?;
            }
            if index == 0 {
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperRight)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 13))
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
        }
        Ok(())
    })
}

/// Draw `chart`'s series labels at `position` in a nearly opaque white box with a black border:
/// the legend of the realism and loudness pictures.
pub fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(|e| e.to_string())
}
