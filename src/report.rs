//! Error-against-time reports: the per-pass CSV, log-log plots, and labelled image strips.

use crate::error::{Error, Result};
use crate::metrics::RELMSE_EPSILON;
use crate::output::{Film, write_atomically};
use crate::render::PassReport;
use plotters::prelude::*;
use std::io::Write;
use std::path::Path;
use std::sync::Once;

const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is embedded, so it is valid; nothing to report if registration fails.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn io(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Invalid(format!("{}: {e}", path.display()))
}

/// One row per pass: pass, spp, device_seconds, wall_seconds, rmse, relmse, mae,
/// estimated_relmse, non_finite_pixels, non_finite_samples (empty cells where not measured).
pub fn write_csv(path: &Path, passes: &[PassReport]) -> Result<()> {
    let mut s = String::from(
        "pass,spp,device_seconds,wall_seconds,rmse,relmse,mae,estimated_relmse,non_finite_pixels,non_finite_samples\n",
    );
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.6e}")).unwrap_or_default();
    for p in passes {
        s += &format!(
            "{},{},{:.6},{:.6},{},{},{},{},{},{}\n",
            p.pass,
            p.spp,
            p.device_seconds,
            p.wall_seconds,
            opt(p.error.map(|e| e.rmse)),
            opt(p.error.map(|e| e.relmse)),
            opt(p.error.map(|e| e.mae)),
            opt(p.estimated_relmse),
            p.error
                .map(|e| e.non_finite_pixels.to_string())
                .unwrap_or_default(),
            p.non_finite_samples
        );
    }
    write_atomically(path, |tmp| {
        std::fs::File::create(tmp)
            .and_then(|mut f| f.write_all(s.as_bytes()))
            .map_err(|e| io(path, e))
    })
}

/// Writes an RGB8 buffer as PNG (through a temporary file, like every output).
fn save_png(path: &Path, w: u32, h: u32, buf: Vec<u8>) -> Result<()> {
    let image = image::RgbImage::from_raw(w, h, buf).expect("buffer size");
    write_atomically(path, |tmp| {
        image
            .save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| io(path, e))
    })
}

/// A named curve of (seconds, error) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Log-log plot of error against time, one curve per series, written as PNG.
pub fn plot_error(path: &Path, title: &str, y_label: &str, series: &[Series]) -> Result<()> {
    register_font();
    let (w, h) = (900u32, 560u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let pts = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
    };
    if pts().next().is_none() {
        return Err(io(path, "no positive points to plot"));
    }
    let (x0, x1) = pts().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let (y0, y1) = pts().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    let pad = |lo: f64, hi: f64| (lo / 1.5, if hi > lo { hi * 1.5 } else { lo * 10.0 });
    let (x0, x1) = pad(x0, x1);
    let (y0, y1) = pad(y0, y1);
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let e = |e: &dyn std::fmt::Display| io(path, e);
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc("seconds")
            .y_desc(y_label)
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .draw()
            .map_err(|x| e(&x))?;
        for (i, s) in series.iter().enumerate() {
            let c = COLORS[i % COLORS.len()];
            let p: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.0 > 0.0 && p.1 > 0.0)
                .collect();
            chart
                .draw_series(LineSeries::new(p.clone(), c.stroke_width(2)))
                .map_err(|x| e(&x))?
                .label(s.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart
                .draw_series(p.iter().map(|&q| Circle::new(q, 3, c.filled())))
                .map_err(|x| e(&x))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    save_png(path, w, h, buf)
}

fn srgb(v: f32) -> u8 {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// False colour for t in [0, 1] (dark blue → green → yellow), a cheap viridis-like ramp.
fn ramp(t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let stops = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (stops[i], stops[i + 1]);
    [
        (a.0 + (b.0 - a.0) * f) as u8,
        (a.1 + (b.1 - a.1) * f) as u8,
        (a.2 + (b.2 - a.2) * f) as u8,
    ]
}

/// A panel of an image strip: a label, an image, and under it the per-pixel relative squared
/// error (I-R)²/(R²+ε) against `reference`, or the half-buffer estimate in `error` when given.
pub struct Panel<'a> {
    pub label: String,
    pub film: &'a Film,
    pub error: Vec<f64>,
}

/// Per-pixel relative squared error against a reference, averaged over the channels.
pub fn relative_error_map(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Vec<f64> {
    image
        .iter()
        .zip(reference)
        .map(|(i, r)| {
            (0..3)
                .map(|c| {
                    let d = f64::from(i[c]) - f64::from(r[c]);
                    d * d / (f64::from(r[c]).powi(2) + RELMSE_EPSILON)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

/// Columns of (label, image, error heat-map on a log scale 1e-4 … 1), written as PNG.
pub fn image_strip(path: &Path, panels: &[Panel]) -> Result<()> {
    register_font();
    let Some(first) = panels.first() else {
        return Err(io(path, "no panels"));
    };
    let (pw, ph) = (first.film.width, first.film.height);
    let label_h = 28u32;
    let (w, h) = (pw * panels.len() as u32, label_h + 2 * ph + label_h);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    for (k, p) in panels.iter().enumerate() {
        for y in 0..ph {
            for x in 0..pw {
                let i = (y * pw + x) as usize;
                let px = |row: u32| (((row * w) + k as u32 * pw + x) * 3) as usize;
                let o = px(label_h + y);
                for c in 0..3 {
                    buf[o + c] = srgb(p.film.beauty[i][c]);
                }
                let e = p.error.get(i).copied().unwrap_or(0.0).max(1e-12);
                let t = (e.log10() + 4.0) / 4.0;
                let o = px(label_h + ph + y);
                buf[o..o + 3].copy_from_slice(&ramp(t));
            }
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let style = ("sans-serif", 16).into_font().color(&BLACK);
        for (k, p) in panels.iter().enumerate() {
            root.draw_text(&p.label, &style, (k as i32 * pw as i32 + 6, 6))
                .map_err(|e| io(path, e))?;
        }
        root.draw_text(
            "relative squared error, log scale 1e-4 (dark) to 1 (yellow)",
            &style,
            (6, (label_h + 2 * ph + 6) as i32),
        )
        .map_err(|e| io(path, e))?;
        root.present().map_err(|e| io(path, e))?;
    }
    save_png(path, w, h, buf)
}
