//! The live views: the string's shape with the contact point, history traces (contact force,
//! energy on a log scale) and the DSP load bar. Drawing only; the data comes from
//! [`crate::meter`] through the editor.

use std::collections::VecDeque;

use egui::{Align, Align2, Color32, FontId, Pos2, Rect, RichText, Sense, Stroke, StrokeKind, Ui, Vec2, pos2, vec2};
use qsa_dsp::instrument::Monitor;

/// Snapshots kept for the traces: 5 s at the audio thread's 30 per second.
pub const HISTORY: usize = 150;

/// Colours of the views.
pub const STRING_COLOR: Color32 = Color32::from_rgb(120, 200, 255);
pub const CONTACT_COLOR: Color32 = Color32::from_rgb(255, 150, 60);
pub const ENERGY_COLOR: Color32 = Color32::from_rgb(120, 220, 120);
pub const ACTIVE_COLOR: Color32 = Color32::from_rgb(90, 200, 90);
const GRID_COLOR: Color32 = Color32::from_gray(60);
const AXIS_COLOR: Color32 = Color32::from_gray(120);
const BACKGROUND: Color32 = Color32::from_gray(18);
const TEXT: Color32 = Color32::from_gray(200);

/// Width of the traces' left margin, where their axis labels go (logical pixels).
const AXIS_GUTTER: f32 = 40.0;

/// Smallest energy the log trace shows (J).
const ENERGY_FLOOR: f64 = 1e-12;
/// Decades the energy trace spans.
const ENERGY_DECADES: f64 = 8.0;

/// The GUI side's record of recent snapshots: energy and contact force of the loudest voice.
#[derive(Debug)]
pub struct History {
    energy: VecDeque<f64>,
    force: VecDeque<f64>,
    /// Display scale of the string shape (m): follows the peak, decays slowly.
    shape_scale: f32,
}

impl Default for History {
    fn default() -> Self {
        Self {
            energy: VecDeque::with_capacity(HISTORY),
            force: VecDeque::with_capacity(HISTORY),
            shape_scale: MIN_SHAPE_SCALE,
        }
    }
}

/// The shape view's scale never goes below this (m), so a silent string draws flat.
const MIN_SHAPE_SCALE: f32 = 1e-6;

impl History {
    /// Record a snapshot.
    pub fn push(&mut self, monitor: &Monitor) {
        if self.energy.len() == HISTORY {
            self.energy.pop_front();
            self.force.pop_front();
        }
        self.energy.push_back(monitor.energy);
        self.force.push_back(monitor.force.abs());
        let peak = monitor.shape.iter().fold(0.0f32, |m, y| m.max(y.abs()));
        self.shape_scale = (peak * 1.1).max(self.shape_scale * 0.95).max(MIN_SHAPE_SCALE);
    }
}

/// A framed plot area of `size`, with `title` and `value` written in its top corners.
fn plot_area(ui: &mut Ui, size: Vec2, title: &str, value: &str) -> (egui::Painter, Rect) {
    let (response, painter) = ui.allocate_painter(size, Sense::hover());
    let rect = response.rect;
    painter.rect_filled(rect, 4.0, BACKGROUND);
    painter.rect_stroke(rect, 4.0, Stroke::new(1.0, GRID_COLOR), StrokeKind::Inside);
    let font = FontId::proportional(12.0);
    painter.text(rect.left_top() + vec2(8.0, 5.0), Align2::LEFT_TOP, title, font.clone(), TEXT);
    painter.text(rect.right_top() + vec2(-8.0, 5.0), Align2::RIGHT_TOP, value, font, TEXT);
    // The plotting area, below the titles.
    (painter, Rect::from_min_max(rect.min + vec2(8.0, 24.0), rect.max - vec2(8.0, 8.0)))
}

/// The string's displacement along its length (nut or bridge at each end), scaled to fit, with a
/// marker where the hammer or slide touches it (filled when in contact).
pub fn string_shape(ui: &mut Ui, size: Vec2, monitor: &Monitor, history: &History) {
    let scale = history.shape_scale;
    let title = format!("String shape, {:.3} m long", monitor.length);
    let value = format!("full scale ±{}", metres(f64::from(scale)));
    let (painter, area) = plot_area(ui, size, &title, &value);
    let mid = area.center().y;
    painter.hline(area.x_range(), mid, Stroke::new(1.0, GRID_COLOR));
    let n = monitor.shape.len();
    let half = area.height() / 2.0;
    let point = |k: usize, y: f32| {
        pos2(area.left() + area.width() * k as f32 / (n - 1) as f32, mid - half * (y / scale).clamp(-1.0, 1.0))
    };
    let points: Vec<Pos2> = monitor.shape.iter().enumerate().map(|(k, &y)| point(k, y)).collect();
    painter.line(points, Stroke::new(2.0, STRING_COLOR));
    // Ends of the string.
    for x in [area.left(), area.right()] {
        painter.vline(x, mid - 6.0..=mid + 6.0, Stroke::new(2.0, TEXT));
    }
    if monitor.sounding == 0 {
        painter.text(area.center() + vec2(0.0, 18.0), Align2::CENTER_TOP, "silent", FontId::proportional(12.0), TEXT);
        return;
    }
    // The contact point: interpolate the shape there.
    let c = monitor.contact_position.clamp(0.0, 1.0) as f32;
    let at = c * (n - 1) as f32;
    let k = (at.floor() as usize).min(n - 2);
    let y = monitor.shape[k] + (at - k as f32) * (monitor.shape[k + 1] - monitor.shape[k]);
    let x = area.left() + area.width() * c;
    let p = pos2(x, mid - half * (y / scale).clamp(-1.0, 1.0));
    painter.vline(x, area.y_range(), Stroke::new(1.0, CONTACT_COLOR.gamma_multiply(0.5)));
    let touching = monitor.compression > 0.0;
    if touching {
        painter.circle_filled(p, 5.0, CONTACT_COLOR);
    } else {
        painter.circle_stroke(p, 5.0, Stroke::new(1.5, CONTACT_COLOR));
    }
    let label = format!("contact at {:.2} L{}", c, if touching { ", touching" } else { "" });
    // Beside the contact line, on the side with more room, at the edge the string is away from.
    let (label_x, h) = if c > 0.7 { (x - 6.0, Align::RIGHT) } else { (x + 6.0, Align::LEFT) };
    let (label_y, v) = if p.y > mid { (area.top() + 2.0, Align::TOP) } else { (area.bottom() - 2.0, Align::BOTTOM) };
    painter.text(pos2(label_x, label_y), Align2([h, v]), label, FontId::proportional(11.0), CONTACT_COLOR);
}

/// A history trace: `values` mapped to 0..1 by `map`, newest at the right.
fn trace(painter: &egui::Painter, area: Rect, values: &VecDeque<f64>, map: impl Fn(f64) -> f32, color: Color32) {
    if values.len() < 2 {
        return;
    }
    let step = area.width() / (HISTORY - 1) as f32;
    let start = area.right() - step * (values.len() - 1) as f32;
    let points: Vec<Pos2> = values
        .iter()
        .enumerate()
        .map(|(k, &v)| pos2(start + step * k as f32, area.bottom() - area.height() * map(v).clamp(0.0, 1.0)))
        .collect();
    painter.line(points, Stroke::new(1.5, color));
}

/// The contact force of the loudest voice over the last seconds, linear, auto-scaled.
pub fn force_trace(ui: &mut Ui, size: Vec2, monitor: &Monitor, history: &History) {
    let top = history.force.iter().fold(0.0f64, |m, &f| m.max(f));
    let title = format!("Contact force (last {:.0} s)", HISTORY as f64 / 30.0);
    let value = format!("{:.3} N, peak {:.2} N", monitor.force.abs(), top);
    let (painter, area) = plot_area(ui, size, &title, &value);
    let area = area.with_min_x(area.left() + AXIS_GUTTER);
    let top = if top > 0.0 { top } else { 1.0 };
    for (y, label, align) in
        [(area.top(), newtons(top), Align2::RIGHT_TOP), (area.bottom(), "0 N".to_owned(), Align2::RIGHT_BOTTOM)]
    {
        painter.hline(area.x_range(), y, Stroke::new(1.0, GRID_COLOR));
        axis_label(&painter, pos2(area.left(), y), align, label);
    }
    trace(&painter, area, &history.force, |f| (f / top) as f32, CONTACT_COLOR);
}

/// The loudest voice's energy over the last seconds on a log scale, a grid line per decade. The
/// top decade follows the largest energy, but the scale never reaches below the floor: at rest
/// the trace lies on the bottom line.
pub fn energy_trace(ui: &mut Ui, size: Vec2, monitor: &Monitor, history: &History) {
    let max = history.energy.iter().fold(ENERGY_FLOOR, |m, &e| m.max(e));
    let top = max.log10().ceil().max(ENERGY_FLOOR.log10() + ENERGY_DECADES);
    let bottom = top - ENERGY_DECADES;
    let value = format!("{:.3e} J", monitor.energy);
    let (painter, area) = plot_area(ui, size, "Energy of the loudest voice (log)", &value);
    let area = area.with_min_x(area.left() + AXIS_GUTTER);
    let decades = ENERGY_DECADES as i32;
    for d in 0..=decades {
        let y = area.bottom() - area.height() * d as f32 / ENERGY_DECADES as f32;
        painter.hline(area.x_range(), y, Stroke::new(1.0, GRID_COLOR));
        // Every other decade; not the top line, whose label would reach into the title.
        if d % 2 == 0 && d < decades {
            axis_label(&painter, pos2(area.left(), y), Align2::RIGHT_CENTER, format!("1e{} J", bottom as i32 + d));
        }
    }
    let map = |e: f64| ((e.max(ENERGY_FLOOR).log10() - bottom) / ENERGY_DECADES) as f32;
    trace(&painter, area, &history.energy, map, ENERGY_COLOR);
}

/// An axis label in the gutter left of a trace, `align`ed to the point `at` on the trace's
/// left edge.
fn axis_label(painter: &egui::Painter, at: Pos2, align: Align2, label: String) {
    painter.text(at - vec2(4.0, 0.0), align, label, FontId::proportional(10.0), AXIS_COLOR);
}

/// A force with three significant digits.
fn newtons(f: f64) -> String {
    if f >= 99.95 {
        format!("{f:.0} N")
    } else if f >= 9.995 {
        format!("{f:.1} N")
    } else {
        format!("{f:.2} N")
    }
}

/// A section's mode mark: a dot (filled for the mode playing, hollow for the other) and the
/// words. The dot is drawn, as egui's default fonts have no circle glyphs.
pub fn mode_mark(ui: &mut Ui, active: bool) {
    ui.spacing_mut().item_spacing.x = 4.0;
    let (rect, _) = ui.allocate_exact_size(vec2(8.0, 8.0), Sense::hover());
    if active {
        ui.painter().circle_filled(rect.center(), 4.0, ACTIVE_COLOR);
        ui.label(RichText::new("active mode").color(ACTIVE_COLOR).small());
    } else {
        let color = ui.visuals().weak_text_color();
        ui.painter().circle_stroke(rect.center(), 3.5, Stroke::new(1.0, color));
        ui.label(RichText::new("other mode").weak().small());
    }
}

/// The DSP load as a bar (green, then yellow above 50 %, red above 80 %) with a peak tick.
pub fn load_bar(ui: &mut Ui, size: Vec2, load: f32, peak: f32) {
    let (response, painter) = ui.allocate_painter(size, Sense::hover());
    let rect = response.rect;
    painter.rect_filled(rect, 3.0, BACKGROUND);
    let fraction = load.clamp(0.0, 1.0);
    let color = if load > 0.8 {
        Color32::from_rgb(230, 70, 60)
    } else if load > 0.5 {
        Color32::from_rgb(230, 200, 60)
    } else {
        Color32::from_rgb(90, 200, 90)
    };
    let mut filled = rect;
    filled.set_width(rect.width() * fraction);
    painter.rect_filled(filled, 3.0, color);
    let x = rect.left() + rect.width() * peak.clamp(0.0, 1.0);
    painter.vline(x, rect.y_range(), Stroke::new(2.0, TEXT));
    painter.rect_stroke(rect, 3.0, Stroke::new(1.0, GRID_COLOR), StrokeKind::Inside);
}

/// A length with a readable unit. A value that would round up to 1000 of a unit is written in
/// the next (1e-6 as an `f32` is 999.99997 nm: "1.00 µm", not "1000.0 nm").
pub fn metres(x: f64) -> String {
    let a = x.abs();
    if a >= 0.999_995e-3 {
        format!("{:.2} mm", x * 1e3)
    } else if a >= 0.999_95e-6 {
        format!("{:.2} µm", x * 1e6)
    } else {
        format!("{:.1} nm", x * 1e9)
    }
}

/// The name of a MIDI key (60 is C4).
pub fn note_name(key: u8) -> String {
    const NAMES: [&str; 12] = ["C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B"];
    format!("{}{}", NAMES[usize::from(key % 12)], i32::from(key / 12) - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_units() {
        assert_eq!(note_name(60), "C4");
        assert_eq!(note_name(45), "A2");
        assert_eq!(note_name(0), "C-1");
        assert_eq!(metres(2.5e-3), "2.50 mm");
        assert_eq!(metres(-3e-6), "-3.00 µm");
        assert_eq!(metres(4e-9), "4.0 nm");
        assert_eq!(metres(f64::from(MIN_SHAPE_SCALE)), "1.00 µm");
        assert_eq!(metres(f64::from(1e-3f32)), "1.00 mm");
        assert_eq!(metres(999.9e-6), "999.90 µm");
        assert_eq!(newtons(0.5), "0.50 N");
        assert_eq!(newtons(9.999), "10.0 N");
        assert_eq!(newtons(123.4), "123 N");
    }

    #[test]
    fn history_is_bounded_and_scale_follows_the_peak() {
        let mut h = History::default();
        let mut m = Monitor::default();
        m.shape[10] = 1e-3;
        for _ in 0..2 * HISTORY {
            h.push(&m);
        }
        assert_eq!(h.energy.len(), HISTORY);
        assert!((h.shape_scale - 1.1e-3).abs() < 1e-9);
        m.shape[10] = 0.0;
        for _ in 0..1000 {
            h.push(&m);
        }
        assert_eq!(h.shape_scale, MIN_SHAPE_SCALE);
    }
}
