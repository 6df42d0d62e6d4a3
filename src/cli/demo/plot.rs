//! SVG plots of a run: the map with the path coloured by empowerment, and its time series.
//!
//! Written out by hand rather than with a plotting crate: plotters lays out text through a
//! system font stack (font-kit) that a fresh machine need not have, and the two panels here
//! need only rectangles, circles, polylines and text.

use std::fmt::Write;

/// What the map panel draws: the world's bounds and its obstacles, each
/// `(x_min, y_min, x_max, y_max)` in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct Map {
    /// The walls' inner outline.
    pub bounds: [f64; 4],
    /// The obstacles inside.
    pub obstacles: Vec<[f64; 4]>,
}

/// One scored moment of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightSample {
    /// Seconds since the start.
    pub t: f64,
    /// Position, metres.
    pub x: f64,
    /// Position, metres.
    pub y: f64,
    /// C-STEP score, nats.
    pub empowerment: f64,
    /// Empowered reward.
    pub reward: f64,
}

const WIDTH: f64 = 900.0;
const MAP_HEIGHT: f64 = 480.0;
const SERIES_HEIGHT: f64 = 260.0;
const MARGIN: f64 = 50.0;

/// The SVG document for `samples` taken on `map`.
pub fn flight_svg(map: &Map, samples: &[FlightSample]) -> String {
    let mut svg = String::new();
    let height = MAP_HEIGHT + SERIES_HEIGHT;
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let (lo, hi) = range(samples.iter().map(|s| s.empowerment));
    map_panel(&mut svg, map, samples, lo, hi);
    series_panel(&mut svg, samples);
    svg.push_str("</svg>\n");
    svg
}

fn map_panel(svg: &mut String, map: &Map, samples: &[FlightSample], lo: f64, hi: f64) {
    let [x0, y0, x1, y1] = map.bounds;
    let scale = ((WIDTH - 2.0 * MARGIN) / (x1 - x0)).min((MAP_HEIGHT - 2.0 * MARGIN) / (y1 - y0));
    let px = |x: f64| MARGIN + (x - x0) * scale;
    let py = |y: f64| MAP_HEIGHT - MARGIN - (y - y0) * scale;
    let _ = writeln!(
        svg,
        r#"<text x="{MARGIN}" y="28" font-size="16">C-STEP along the path (colour: empowerment, nats)</text>"#
    );
    let rect = |svg: &mut String, [a, b, c, d]: [f64; 4], style: &str| {
        let _ = writeln!(
            svg,
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" {style}/>"#,
            px(a),
            py(d),
            (c - a) * scale,
            (d - b) * scale
        );
    };
    rect(
        svg,
        map.bounds,
        r##"fill="#f7f7f7" stroke="#333" stroke-width="3""##,
    );
    for &obstacle in &map.obstacles {
        rect(svg, obstacle, r##"fill="#800000""##);
    }
    for s in samples {
        let _ = writeln!(
            svg,
            r#"<circle cx="{:.1}" cy="{:.1}" r="5" fill="{}"><title>t={:.1}s E={:.3}</title></circle>"#,
            px(s.x),
            py(s.y),
            colour((s.empowerment - lo) / (hi - lo).max(1e-9)),
            s.t,
            s.empowerment
        );
    }
    // Colour bar.
    let (bx, by) = (WIDTH - MARGIN - 200.0, 40.0);
    for k in 0..50 {
        let _ = writeln!(
            svg,
            r#"<rect x="{:.1}" y="{by}" width="4.2" height="12" fill="{}"/>"#,
            bx + k as f64 * 4.0,
            colour(k as f64 / 49.0)
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{bx}" y="{}" text-anchor="middle">{lo:.2}</text><text x="{}" y="{}" text-anchor="middle">{hi:.2}</text>"#,
        by + 28.0,
        bx + 200.0,
        by + 28.0
    );
}

fn series_panel(svg: &mut String, samples: &[FlightSample]) {
    let top = MAP_HEIGHT + 20.0;
    let bottom = MAP_HEIGHT + SERIES_HEIGHT - MARGIN;
    let (t0, t1) = range(samples.iter().map(|s| s.t));
    let (v0, v1) = range(
        samples
            .iter()
            .flat_map(|s| [s.empowerment, s.reward])
            .chain([0.0]),
    );
    let px = |t: f64| MARGIN + (t - t0) / (t1 - t0).max(1e-9) * (WIDTH - 2.0 * MARGIN);
    let py = |v: f64| bottom - (v - v0) / (v1 - v0).max(1e-9) * (bottom - top);
    let _ = writeln!(
        svg,
        r##"<line x1="{MARGIN}" y1="{bottom}" x2="{}" y2="{bottom}" stroke="#333"/><line x1="{MARGIN}" y1="{top}" x2="{MARGIN}" y2="{bottom}" stroke="#333"/>"##,
        WIDTH - MARGIN
    );
    let _ = writeln!(
        svg,
        r##"<line x1="{MARGIN}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#bbb" stroke-dasharray="4"/>"##,
        py(0.0),
        WIDTH - MARGIN
    );
    for (value, label) in [(v0, v0), (v1, v1)] {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{:.1}" text-anchor="end">{label:.2}</text>"#,
            MARGIN - 6.0,
            py(value) + 4.0
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">time (s): {t0:.1} … {t1:.1}</text>"#,
        WIDTH / 2.0,
        bottom + 30.0
    );
    for (pick, colour, name, offset) in [
        (0, "#1f77b4", "empowerment (nats)", 0.0),
        (1, "#d62728", "empowered reward", 180.0),
    ] {
        let points: Vec<String> = samples
            .iter()
            .map(|s| {
                let v = if pick == 0 { s.empowerment } else { s.reward };
                format!("{:.1},{:.1}", px(s.t), py(v))
            })
            .collect();
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="2"/>"#,
            points.join(" ")
        );
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" fill="{colour}">{name}</text>"#,
            MARGIN + 10.0 + offset,
            top + 4.0
        );
    }
}

/// The smallest and largest of `values` (0..1 when there are none).
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

/// A perceptually ordered colour for `u ∈ [0, 1]` (dark purple → teal → yellow, like viridis).
fn colour(u: f64) -> String {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let u = u.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (u.floor() as usize).min(STOPS.len() - 2);
    let f = u - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    format!(
        "#{:02x}{:02x}{:02x}",
        mix(a.0, b.0),
        mix(a.1, b.1),
        mix(a.2, b.2)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_svg_holds_the_arena_one_dot_per_sample_and_both_series() {
        let samples: Vec<FlightSample> = (0..20)
            .map(|k| FlightSample {
                t: k as f64 * 0.1,
                x: k as f64 * 0.2,
                y: -1.0,
                empowerment: 1.0 + k as f64 * 0.1,
                reward: 0.5,
            })
            .collect();
        let map = Map {
            bounds: [-0.5, -1.75, 4.5, 0.75],
            obstacles: vec![[0.5, -0.25, 2.5, 0.25], [3.0, 0.0, 3.5, 0.5]],
        };
        let svg = flight_svg(&map, &samples);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<circle").count(), 20);
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("#800000").count(), 2, "the obstacles");
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn colours_run_from_dark_to_yellow() {
        assert_eq!(colour(0.0), "#440154");
        assert_eq!(colour(1.0), "#fde725");
        assert_eq!(colour(-3.0), colour(0.0));
    }
}
