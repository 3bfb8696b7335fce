//! The status bar: lines of text (DejaVu Sans, the plots' font) and the estimated error against
//! time as a small log-log curve, drawn into the frame on the host.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

pub struct Text {
    font: FontRef<'static>,
    scale: PxScale,
}

pub type Rgb = [u8; 3];

impl Text {
    pub fn new(px: f32) -> Text {
        Text {
            font: FontRef::try_from_slice(FONT).expect("the embedded font parses"),
            scale: PxScale::from(px),
        }
    }

    /// Line height in pixels.
    pub fn line(&self) -> u32 {
        self.font.as_scaled(self.scale).height().ceil() as u32 + 2
    }

    /// Draws `text` with its top-left corner at (x, y), clipped to the frame and to `right`.
    pub fn draw(&self, frame: &mut Frame, x: u32, y: u32, right: u32, text: &str, color: Rgb) {
        let f = self.font.as_scaled(self.scale);
        let mut pen = x as f32;
        let baseline = y as f32 + f.ascent();
        let mut last = None;
        for ch in text.chars() {
            let id = f.glyph_id(ch);
            if let Some(prev) = last {
                pen += f.kern(prev, id);
            }
            last = Some(id);
            let glyph = id.with_scale_and_position(self.scale, point(pen, baseline));
            pen += f.h_advance(id);
            if pen > right as f32 {
                break;
            }
            if let Some(outline) = self.font.outline_glyph(glyph) {
                let b = outline.px_bounds();
                outline.draw(|gx, gy, coverage| {
                    let (px, py) = (b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64);
                    frame.blend(px, py, color, coverage);
                });
            }
        }
    }
}

/// An RGBA8 frame on the host.
pub struct Frame<'a> {
    pub pixels: &'a mut [u8],
    pub width: u32,
    pub height: u32,
}

impl Frame<'_> {
    pub fn blend(&mut self, x: i64, y: i64, color: Rgb, alpha: f32) {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return;
        }
        let o = 4 * (y as usize * self.width as usize + x as usize);
        let a = alpha.clamp(0.0, 1.0);
        for (d, &c) in self.pixels[o..o + 3].iter_mut().zip(&color) {
            *d = (f32::from(*d) + (f32::from(c) - f32::from(*d)) * a).round() as u8;
        }
        self.pixels[o + 3] = 255;
    }

    /// Fills rows [y0, y1) with `color`.
    pub fn fill_rows(&mut self, y0: u32, y1: u32, color: Rgb) {
        let w = self.width as usize;
        for y in y0.min(self.height)..y1.min(self.height) {
            for x in 0..w {
                let o = 4 * (y as usize * w + x);
                self.pixels[o..o + 4].copy_from_slice(&[color[0], color[1], color[2], 255]);
            }
        }
    }

    /// Points (seconds, relMSE) on log-log axes fitted to them, in the box at (x, y) of `size`.
    pub fn curve(&mut self, x: u32, y: u32, size: [u32; 2], points: &[(f64, f64)], color: Rgb) {
        let logs: Vec<(f64, f64)> = points
            .iter()
            .filter(|(t, e)| *t > 0.0 && *e > 0.0)
            .map(|(t, e)| (t.log10(), e.log10()))
            .collect();
        if logs.len() < 2 || size[0] < 4 || size[1] < 4 {
            return;
        }
        let range = |f: fn(&(f64, f64)) -> f64| {
            let lo = logs.iter().map(f).fold(f64::INFINITY, f64::min);
            let hi = logs.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
            (lo, (hi - lo).max(1e-6))
        };
        let ((t0, dt), (e0, de)) = (range(|p| p.0), range(|p| p.1));
        for &(t, e) in &logs {
            let px = f64::from(x) + (t - t0) / dt * f64::from(size[0] - 2);
            let py = f64::from(y) + (1.0 - (e - e0) / de) * f64::from(size[1] - 2);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                self.blend(px as i64 + dx, py as i64 + dy, color, 1.0);
            }
        }
    }
}
