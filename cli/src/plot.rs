//! Plots on a [`Scene`]: axes with ticks at round numbers, labels with their units, a legend,
//! and a colour scale. Data coordinates are whatever the plot's axes say (mm, degrees, kgf cm,
//! s); the scene is in px.

use crate::picture::{Anchor, Scene, Shape, Style};

/// Line colours, in order (colour-blind friendly).
pub const PALETTE: [&str; 8] = [
    "#0072b2", "#e69f00", "#009e73", "#cc79a7", "#56b4e9", "#d55e00", "#000000", "#f0e442",
];

/// A plot's rectangle and the data ranges it shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axes {
    /// Left edge, px.
    pub left: f64,
    /// Top edge, px.
    pub top: f64,
    /// Width, px.
    pub width: f64,
    /// Height, px.
    pub height: f64,
    /// The x range shown (data units).
    pub x: (f64, f64),
    /// The y range shown (data units).
    pub y: (f64, f64),
    /// Whether the y axis has numbered ticks (not for categories).
    pub y_ticks: bool,
}

/// Round-number ticks covering `lo..=hi`: about `count` of them, steps of 1, 2 or 5 times a
/// power of ten.
pub fn ticks(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    if hi <= lo || !lo.is_finite() || !hi.is_finite() {
        return vec![lo];
    }
    let raw = (hi - lo) / count.max(1) as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * power);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A range widened to round numbers (for axes that start and end on a tick).
pub fn nice_range(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, hi + 1.0)
    };
    let t = ticks(lo, hi, 5);
    let step = if t.len() > 1 { t[1] - t[0] } else { 1.0 };
    ((lo / step).floor() * step, (hi / step).ceil() * step)
}

fn label(value: f64) -> String {
    let text = format!("{value:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_string()
    } else {
        text.to_string()
    }
}

impl Axes {
    /// A data point in px.
    pub fn px(&self, x: f64, y: f64) -> [f64; 2] {
        [
            self.left + (x - self.x.0) / (self.x.1 - self.x.0) * self.width,
            self.top + self.height - (y - self.y.0) / (self.y.1 - self.y.0) * self.height,
        ]
    }

    /// The frame, grid lines and tick labels, the axis labels (with units) and the title.
    pub fn draw(&self, scene: &mut Scene, title: &str, x_label: &str, y_label: &str) {
        let (l, t, w, h) = (self.left, self.top, self.width, self.height);
        for x in ticks(self.x.0, self.x.1, 6) {
            let [px, _] = self.px(x, self.y.0);
            scene.add(
                "grid",
                Shape::Line([px, t], [px, t + h]),
                Style::stroke("#e6e6e6", 1.0),
            );
            scene.text("tick", [px, t + h + 15.0], &label(x), 11.0, Anchor::Middle);
        }
        let y_ticks = if self.y_ticks {
            ticks(self.y.0, self.y.1, 6)
        } else {
            Vec::new()
        };
        for y in y_ticks {
            let [_, py] = self.px(self.x.0, y);
            scene.add(
                "grid",
                Shape::Line([l, py], [l + w, py]),
                Style::stroke("#e6e6e6", 1.0),
            );
            scene.text("tick", [l - 6.0, py + 4.0], &label(y), 11.0, Anchor::End);
        }
        scene.add(
            "axes",
            Shape::Path {
                points: vec![[l, t], [l + w, t], [l + w, t + h], [l, t + h]],
                closed: true,
            },
            Style::stroke("#444", 1.0),
        );
        scene.text(
            "title",
            [l + w / 2.0, t - 10.0],
            title,
            14.0,
            Anchor::Middle,
        );
        scene.text(
            "x-label",
            [l + w / 2.0, t + h + 34.0],
            x_label,
            12.0,
            Anchor::Middle,
        );
        scene.add(
            "y-label",
            Shape::Text {
                at: [l - 44.0, t + h / 2.0],
                text: y_label.to_string(),
                size_px: 12.0,
                anchor: Anchor::Middle,
                rotate_deg: -90.0,
            },
            Style::fill("#000"),
        );
    }

    /// A polyline of data points.
    pub fn line(&self, scene: &mut Scene, class: &'static str, points: &[[f64; 2]], style: Style) {
        scene.add(
            class,
            Shape::Path {
                points: points.iter().map(|p| self.px(p[0], p[1])).collect(),
                closed: false,
            },
            style,
        );
    }
}

/// A legend: a short line (or box) of each colour and its label, from `at` (px) downwards.
pub fn legend(scene: &mut Scene, at: [f64; 2], entries: &[(&'static str, String, bool)]) {
    for (k, (colour, text, dashed)) in entries.iter().enumerate() {
        let y = at[1] + 18.0 * k as f64;
        let mut style = Style::stroke(colour, 3.0);
        if *dashed {
            style = style.dashed();
        }
        scene.add("legend", Shape::Line([at[0], y], [at[0] + 22.0, y]), style);
        scene.text("legend", [at[0] + 28.0, y + 4.0], text, 11.0, Anchor::Start);
    }
}

/// A colour for `t` in 0..=1 (light yellow to dark blue).
pub fn colour_scale(t: f64) -> &'static str {
    const SCALE: [&str; 9] = [
        "#ffffd9", "#edf8b1", "#c7e9b4", "#7fcdbb", "#41b6c4", "#1d91c0", "#225ea8", "#253494",
        "#081d58",
    ];
    let i = (t.clamp(0.0, 1.0) * (SCALE.len() - 1) as f64).round() as usize;
    SCALE[i]
}

/// A vertical colour bar for `lo..=hi` with a label (units), at `at` (px, top left).
pub fn colour_bar(scene: &mut Scene, at: [f64; 2], height: f64, lo: f64, hi: f64, caption: &str) {
    let steps = 9;
    for k in 0..steps {
        let y = at[1] + height * (1.0 - (k + 1) as f64 / steps as f64);
        scene.add(
            "colour-bar",
            Shape::Path {
                points: vec![
                    [at[0], y],
                    [at[0] + 14.0, y],
                    [at[0] + 14.0, y + height / steps as f64],
                    [at[0], y + height / steps as f64],
                ],
                closed: true,
            },
            Style::fill(colour_scale(k as f64 / (steps - 1) as f64)),
        );
    }
    scene.text(
        "colour-bar",
        [at[0] + 18.0, at[1] + 8.0],
        &label(hi),
        11.0,
        Anchor::Start,
    );
    scene.text(
        "colour-bar",
        [at[0] + 18.0, at[1] + height],
        &label(lo),
        11.0,
        Anchor::Start,
    );
    scene.add(
        "colour-bar",
        Shape::Text {
            at: [at[0] + 50.0, at[1] + height / 2.0],
            text: caption.to_string(),
            size_px: 11.0,
            anchor: Anchor::Middle,
            rotate_deg: -90.0,
        },
        Style::fill("#000"),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(ticks(0.0, 10.0, 5), [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        // 64 / 6 = 10.7 per tick: steps of 20.
        assert_eq!(ticks(-23.0, 41.0, 6), [-20.0, 0.0, 20.0, 40.0]);
        assert_eq!(ticks(0.0, 0.9, 4), [0.0, 0.5]);
        assert_eq!(nice_range(-23.0, 41.0), (-40.0, 60.0));
        let axes = Axes {
            left: 10.0,
            top: 20.0,
            width: 100.0,
            height: 50.0,
            x: (0.0, 10.0),
            y: (-1.0, 1.0),
            y_ticks: true,
        };
        assert_eq!(axes.px(0.0, -1.0), [10.0, 70.0]);
        assert_eq!(axes.px(10.0, 1.0), [110.0, 20.0]);
    }
}
