//! Importance-sampling tables of a dome (environment) light's map, read by `sample_dome`/`dome_hit`
//! in glsl/lights/infinite_lights.glsl (docs/techniques.md, "Dome importance sampling"), for each
//! map convention of glsl/lights/dome_map.glsl.
//!
//! The tables cover a grid of cells in map coordinates (u, v), and a cell's weight is the luminance
//! `lum(tint ⊙ L)` the convention's lookup gives inside it, times the solid angle per unit map
//! area at its centre (sin θ for lat-long maps, 1 for the equal-area square):
//! - illum: the cells are the texels; with the bilinear filter the weight is the texel integral
//!   of the bilinear lookup, a separable (1/8, 3/4, 1/8) tent over the neighbours as the texture's
//!   wrap modes reach them; with the nearest filter, the texel itself.
//! - Mitsuba: the cells lie between texel centres (W columns offset by half a texel, H − 1 rows
//!   from pole to pole), where the lookup is one bilinear patch: the mean of its four corners.
//! - pbrt: the cells are the texels of the square (nearest lookup).
//!
//! Every cell where the radiance can be positive therefore has a positive weight, so the pdf is
//! positive wherever the dome's radiance is (needed when light sampling is used alone, as for the
//! course's diffuse lobe).
//!
//! The tables are a marginal CDF over rows and one conditional CDF per row, accumulated in f64 and
//! stored as f32 with exact 0 and 1 ends. The GPU samples a row and a cell by binary search and a
//! point inside the cell, uniform or, where the lookup's luminance varies enough, drawn from it (the
//! cell's shape: `nodes`, `DOME_SHAPE_*` in glsl/shared/layout.glsl). Each CDF of n intervals has a guide of n buckets: bucket k holds
//! the index range `[lo, hi)` of the intervals that u in [k/n, (k+1)/n) (widened by 1e-6, more than
//! the GPU's rounding of `u n`) can fall in, so the search runs over a few intervals instead of n
//! (O(1) expected steps) and still returns the index of the full search; its pdf is `P(row) P(cell | row) W H / (dω/du dv)` with the
//! probabilities taken as differences of the stored CDFs — exactly the mass the search assigns.

use crate::layout::{DOME_SHAPE_CORNERS, DOME_SHAPE_TENT, DOME_SHAPE_UNIFORM, GpuDomeSampling};
use crate::scene::{DomeConvention, Texture, TextureFilter};
use glam::{DVec3, Vec3};

/// Host side of [`GpuDomeSampling`]: the CDF tables of one map.
#[derive(Clone, Debug)]
pub struct DomeTable {
    pub width: u32,
    pub height: u32,
    /// `height + 1` entries: 0, then the cumulative row probabilities, ending at exactly 1.
    pub marginal: Vec<f32>,
    /// `height` rows of `width + 1` entries, each 0 … 1 (a row of zero weight is uniform).
    pub conditional: Vec<f32>,
    /// Mean texel weight (before normalisation).
    pub integral: f64,
    /// Search guides: `marginal_buckets` of the marginal, then `width` per row of the
    /// conditionals, each the `[lo, hi)` range of intervals a sample in that bucket can fall in.
    pub guides: Vec<[u32; 2]>,
    /// Buckets of the marginal's guide: `MARGINAL_GUIDE` height.
    pub marginal_buckets: u32,
    /// The map's first texel in the scene's texel buffer (set by the caller, which knows the
    /// textures before it); None: light samples do not read the map's texels themselves.
    pub texel_offset: Option<u64>,
    /// The dome's radiance on SH9 in world directions (src/gpu_scene/dome_sh.rs), set by the
    /// caller: the control variates' L_SH.
    pub sh: [[f32; 4]; 9],
    /// `DOME_SHAPE_*`: the density inside a cell.
    pub shape: u32,
    /// With a shape other than uniform: the luminance of texel (i, j) at
    /// `(j + 1) (map width + 2) + i + 1`, for i in -1 ..= map width and j in -1 ..= map height,
    /// wrapped as the convention's lookup wraps (empty otherwise).
    pub nodes: Vec<f32>,
    /// Map width + 2 (0 without nodes).
    pub nodes_width: u32,
}

/// Luminance weights of linear RGB (Rec. 709), as `luminance()` in glsl/shared/common.glsl.
pub fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The cell grid of a map of `width` x `height` texels under `convention`: (columns, rows).
pub fn cells(convention: DomeConvention, width: u32, height: u32) -> (u32, u32) {
    match convention {
        DomeConvention::Mitsuba => (width, height.saturating_sub(1).max(1)),
        DomeConvention::Illum | DomeConvention::Pbrt => (width, height),
    }
}

/// The density inside a sampling cell of a map under `convention` with `filter` (`DOME_SHAPE_*`):
/// shaped where the lookup varies inside a cell (a black map is uniform whatever this says).
pub fn cell_shape(convention: DomeConvention, filter: TextureFilter) -> u32 {
    match (convention, filter) {
        (DomeConvention::Mitsuba, _) => DOME_SHAPE_CORNERS,
        (DomeConvention::Illum, TextureFilter::Bilinear) => DOME_SHAPE_TENT,
        _ => DOME_SHAPE_UNIFORM,
    }
}

/// Builds the tables of `texture` as a dome map whose radiance is `tint ⊙ texel` (the tint is the
/// light's colour; only its relative channel weights matter), laid out as `convention` says.
pub fn build(texture: &Texture, tint: Vec3, convention: DomeConvention) -> DomeTable {
    let (tw, th) = (texture.width as usize, texture.height as usize);
    assert!(
        tw > 0 && th > 0 && texture.texels.len() == tw * th,
        "dome texture {}: {}x{} with {} texels",
        texture.name,
        tw,
        th,
        texture.texels.len()
    );
    let lum =
        |i: i64, j: i64| luminance((tint * texture.texel(i, j).truncate()).as_dvec3()).max(0.0);
    let (cw, ch) = cells(convention, texture.width, texture.height);
    let (w, h) = (cw as usize, ch as usize);
    // Solid angle per unit map area at the centre of row j (up to a constant factor).
    let row_measure = |j: usize| match convention {
        DomeConvention::Pbrt => 1.0,
        _ => (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin(),
    };
    // The luminance of texel rows, each taken once (a cell reads up to 9 texels): entry i + 1 of
    // row jj is lum(i, jj) for i in -1..=tw, so that the filters below read their neighbours
    // as the lookup wraps them.
    let mut rows = LumRows::new(|jj| (-1..=tw as i64).map(|i| lum(i, jj)).collect());
    // Row by row (an 8192 x 4096 map's weights would take 268 MB at once).
    let mut conditional = Vec::with_capacity(h * (w + 1));
    let mut row_sums = Vec::with_capacity(h);
    let mut row = vec![0.0f64; w];
    for j in 0..h {
        let jj = j as i64;
        match (convention, texture.filter) {
            (DomeConvention::Mitsuba, _) => {
                // Between column centres i, i + 1 (periodic) and rows j, j + 1.
                let (r0, r1) = rows.two(jj);
                for (i, weight) in row.iter_mut().enumerate() {
                    let i1 = (i + 1) % tw;
                    let l = 0.25 * (r0[i + 1] + r0[i1 + 1] + r1[i + 1] + r1[i1 + 1]);
                    *weight = l * row_measure(j);
                }
            }
            (DomeConvention::Pbrt, _) | (DomeConvention::Illum, TextureFilter::Nearest) => {
                let r = rows.get(jj);
                for (i, weight) in row.iter_mut().enumerate() {
                    *weight = r[i + 1] * row_measure(j);
                }
            }
            (DomeConvention::Illum, TextureFilter::Bilinear) => {
                // Texel integral of the bilinear reconstruction, wrapped as the lookup wraps.
                const K: [f64; 3] = [0.125, 0.75, 0.125];
                let r = rows.three(jj);
                for (i, weight) in row.iter_mut().enumerate() {
                    let mut s = 0.0;
                    for (b, kb) in K.iter().enumerate() {
                        for (a, ka) in K.iter().enumerate() {
                            s += ka * kb * r[b][i + a];
                        }
                    }
                    *weight = s * row_measure(j);
                }
            }
        }
        let sum: f64 = row.iter().sum();
        row_sums.push(sum);
        conditional.extend(cdf(&row, sum));
    }
    let total: f64 = row_sums.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        // A black (or broken) map: sample by solid angle so that the pdf stays valid.
        conditional.clear();
        for (j, sum) in row_sums.iter_mut().enumerate() {
            row.fill(row_measure(j));
            *sum = row.iter().sum();
            conditional.extend(cdf(&row, *sum));
        }
    }
    // The density inside a cell follows the lookup's luminance where it varies there (a black
    // map is sampled by solid angle above: uniform cells).
    let shape = if total > 0.0 && total.is_finite() {
        cell_shape(convention, texture.filter)
    } else {
        DOME_SHAPE_UNIFORM
    };
    let nodes = if shape == DOME_SHAPE_UNIFORM {
        None
    } else {
        // Mitsuba's lookup is periodic in u whatever the texture's wrap (as its cells above).
        let periodic = convention == DomeConvention::Mitsuba;
        shaped_nodes(shape, tw, th, (w, h), |i, j| {
            lum(if periodic { i.rem_euclid(tw as i64) } else { i }, j)
        })
    };
    // A map smooth everywhere (no sun) keeps uniform cells and no nodes.
    let (shape, nodes_width, nodes) = match nodes {
        Some(nodes) => (shape, tw as u32 + 2, nodes),
        None => (DOME_SHAPE_UNIFORM, 0, Vec::new()),
    };
    let grand: f64 = row_sums.iter().sum();
    let marginal = cdf(&row_sums, grand);
    let mut guides = guide(&marginal, MARGINAL_GUIDE);
    for row in conditional.chunks(w + 1) {
        guides.extend(guide(row, 1));
    }
    DomeTable {
        guides,
        marginal_buckets: h as u32 * MARGINAL_GUIDE,
        texel_offset: None,
        sh: [[0.0; 4]; 9],
        shape,
        nodes,
        nodes_width,
        width: w as u32,
        height: h as u32,
        marginal,
        conditional,
        integral: grand / (w * h) as f64,
    }
}

/// A cell is sampled by its shape (`DOME_SHAPE_*`) when uniform sampling would raise the second
/// moment of `L / pdf` for samples inside it by more than this share (its luminance's squared
/// coefficient of variation over the cell). Below it the shape's extra work (4 to 9 node loads
/// per sample and per pdf, 8% of a camera sample where every cell of a sky is shaped) buys
/// nothing measurable: a smooth sky's cells vary by a few percent (excess ~1e-4), a sun's
/// neighbours by factors (excess ~1).
const SHAPED_EXCESS: f64 = 0.01;

/// The luminance nodes of a `tw` x `th` map for cells of `shape` (`lum(i, j)` for i in -1 ..= tw,
/// j in -1 ..= th, wrapped by the caller as the lookup wraps), with the sign bit set on the first
/// node of each of the `cells` (columns, rows) whose luminance varies enough to pay for a shaped
/// density (the GPU takes every node's magnitude); None when no cell does.
fn shaped_nodes(
    shape: u32,
    tw: usize,
    th: usize,
    (w, h): (usize, usize),
    lum: impl Fn(i64, i64) -> f64,
) -> Option<Vec<f32>> {
    let stride = tw + 2;
    let mut nodes = Vec::with_capacity(stride * (th + 2));
    for j in -1..=th as i64 {
        for i in -1..=tw as i64 {
            nodes.push(lum(i, j) as f32);
        }
    }
    let flags: Vec<usize> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .filter(|&(i, j)| cell_excess(shape, &nodes, stride, i, j) > SHAPED_EXCESS)
        .map(|(i, j)| (j + 1) * stride + i + 1)
        .collect();
    if flags.is_empty() {
        return None;
    }
    for k in flags {
        nodes[k] = -nodes[k];
    }
    Some(nodes)
}

/// The 3 x 3 nodes of cell (i, j) as `dome_cell()` in glsl/lights/infinite_lights.glsl reads
/// them from `nodes` (row stride `stride`, texel (i, j) at `(j + 1) stride + i + 1`).
fn cell_nodes(shape: u32, nodes: &[f32], stride: usize, i: usize, j: usize) -> [[f64; 3]; 3] {
    let g = |di: isize, dj: isize| {
        let k = (j as isize + 1 + dj) as usize * stride + (i as isize + 1 + di) as usize;
        f64::from(nodes[k].abs())
    };
    if shape == DOME_SHAPE_CORNERS {
        let (t, b) = ([g(0, 0), g(1, 0)], [g(0, 1), g(1, 1)]);
        let r0 = [t[0], 0.5 * (t[0] + t[1]), t[1]];
        let r2 = [b[0], 0.5 * (b[0] + b[1]), b[1]];
        let r1 = [
            0.5 * (r0[0] + r2[0]),
            0.5 * (r0[1] + r2[1]),
            0.5 * (r0[2] + r2[2]),
        ];
        [r0, r1, r2]
    } else {
        let row = |dj: isize| {
            let t = [g(-1, dj), g(0, dj), g(1, dj)];
            [0.5 * (t[0] + t[1]), t[1], 0.5 * (t[1] + t[2])]
        };
        let (a, b, c) = (row(-1), row(0), row(1));
        let mid = |x: [f64; 3], y: [f64; 3]| {
            [
                0.5 * (x[0] + y[0]),
                0.5 * (x[1] + y[1]),
                0.5 * (x[2] + y[2]),
            ]
        };
        [mid(a, b), b, mid(b, c)]
    }
}

/// The squared coefficient of variation over cell (i, j) of its piecewise bilinear luminance
/// (`E[f^2] / E[f]^2 - 1`, uniform over the cell): 0 for a black cell.
fn cell_excess(shape: u32, nodes: &[f32], stride: usize, i: usize, j: usize) -> f64 {
    let n = cell_nodes(shape, nodes, stride, i, j);
    // 1D mass matrix of linear elements on [0, 1]: integral of phi_a phi_b.
    const M: [[f64; 2]; 2] = [[1.0 / 3.0, 1.0 / 6.0], [1.0 / 6.0, 1.0 / 3.0]];
    let (mut mean, mut square) = (0.0, 0.0);
    for (qy, qx) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        let v = |y: usize, x: usize| n[qy + y][qx + x];
        mean += 0.25 * 0.25 * (v(0, 0) + v(0, 1) + v(1, 0) + v(1, 1));
        for (y1, x1, y2, x2) in (0..16).map(|k| (k >> 3 & 1, k >> 2 & 1, k >> 1 & 1, k & 1)) {
            square += 0.25 * v(y1, x1) * v(y2, x2) * M[y1][y2] * M[x1][x2];
        }
    }
    if mean > 0.0 {
        square / (mean * mean) - 1.0
    } else {
        0.0
    }
}

/// CDF of non-negative weights with exact ends; all-zero weights give a uniform CDF.
fn cdf(weights: &[f64], sum: f64) -> Vec<f32> {
    let n = weights.len();
    let mut out = Vec::with_capacity(n + 1);
    out.push(0.0f32);
    let mut acc = 0.0f64;
    for (k, &x) in weights.iter().enumerate() {
        acc += x;
        let c = if sum > 0.0 {
            acc / sum
        } else {
            (k + 1) as f64 / n as f64
        };
        out.push(c.min(1.0) as f32);
    }
    out[n] = 1.0;
    out
}

/// Guide buckets per interval of the marginal CDF. Where a sun's rows take most of the mass the
/// other rows crowd the remaining buckets, and each step of the binary search after the guide is
/// a gather on lavapipe: with one bucket a row, a group of 8 lanes waited for 2.3 steps on
/// mitsuba-dome's sky, with 16 for 0.4, and the render took 0.94x the time (pixels identical).
/// The row CDFs keep one bucket a cell: finer row guides (4 or 16 a cell, 1-4 MB on that map)
/// were no faster, their cache misses costing what the saved steps gained
/// (docs/performance-kernels.md, "A finer guide for the dome's marginal").
pub const MARGINAL_GUIDE: u32 = 16;

/// Search guide of a CDF of n intervals (n + 1 entries, see `cdf`) in m = `factor` n buckets:
/// for bucket k of u in [k/m, (k+1)/m), widened by `GUIDE_MARGIN` on both sides, the range
/// `[lo, hi)` of the index i with `cdf[i] <= u < cdf[i + 1]` (the GPU's `cdf_find`; monotone in
/// u, so the ends suffice).
fn guide(cdf: &[f32], factor: u32) -> Vec<[u32; 2]> {
    const GUIDE_MARGIN: f64 = 1e-6;
    const U_MAX: f32 = 0.999_999_94; // the GPU clamps u to this
    let n = cdf.len() - 1;
    let m = n * factor as usize;
    // index(x) = (entries of cdf[..n] <= x).max(1) - 1; both ends rise with k, so each is a
    // pointer swept once along the CDF (the same indices as a binary search, in O(m)).
    let sweep = |p: &mut usize, x: f64| {
        let x = (x.max(0.0) as f32).min(U_MAX);
        while *p < n && cdf[*p] <= x {
            *p += 1;
        }
        (*p).max(1) - 1
    };
    let (mut lo_p, mut hi_p) = (0, 0);
    (0..m)
        .map(|k| {
            let lo = sweep(&mut lo_p, k as f64 / m as f64 - GUIDE_MARGIN);
            let hi = sweep(&mut hi_p, (k + 1) as f64 / m as f64 + GUIDE_MARGIN) + 1;
            [lo as u32, hi as u32]
        })
        .collect()
}

/// The luminance rows of a map, each computed once while the rows are visited in order (the
/// filters read rows j - 1 to j + 1).
struct LumRows<F: Fn(i64) -> Vec<f64>> {
    make: F,
    cache: Vec<(i64, Vec<f64>)>,
}

impl<F: Fn(i64) -> Vec<f64>> LumRows<F> {
    fn new(make: F) -> Self {
        LumRows {
            make,
            cache: Vec::new(),
        }
    }

    fn load(&mut self, jj: i64) -> usize {
        if let Some(k) = self.cache.iter().position(|r| r.0 == jj) {
            return k;
        }
        if self.cache.len() == 3 {
            // The row visited longest ago (rows are visited in increasing order).
            let oldest = (0..3).min_by_key(|&k| self.cache[k].0).unwrap();
            self.cache.swap_remove(oldest);
        }
        self.cache.push((jj, (self.make)(jj)));
        self.cache.len() - 1
    }

    fn get(&mut self, jj: i64) -> &[f64] {
        let k = self.load(jj);
        &self.cache[k].1
    }

    fn two(&mut self, jj: i64) -> (&[f64], &[f64]) {
        self.load(jj);
        self.load(jj + 1);
        (self.find(jj), self.find(jj + 1))
    }

    fn three(&mut self, jj: i64) -> [&[f64]; 3] {
        for d in -1..=1 {
            self.load(jj + d);
        }
        [self.find(jj - 1), self.find(jj), self.find(jj + 1)]
    }

    fn find(&self, jj: i64) -> &[f64] {
        &self.cache.iter().find(|r| r.0 == jj).expect("loaded").1
    }
}

impl DomeTable {
    /// The data to upload as one buffer, in four parts: the marginal CDF, the conditional
    /// CDFs, the guides (u32 pairs), then the cells' luminance nodes.
    pub fn parts(&self) -> [&[u8]; 4] {
        [
            bytemuck::cast_slice(&self.marginal),
            bytemuck::cast_slice(&self.conditional),
            bytemuck::cast_slice(&self.guides),
            bytemuck::cast_slice(&self.nodes),
        ]
    }

    /// The GPU descriptor of the tables uploaded as [`DomeTable::parts`] at device address
    /// `address`, the map's texels in the texel buffer at `texels` (0: not given; the light
    /// samples then look their radiance up as any ray does).
    pub fn gpu(&self, address: u64, texels: u64) -> GpuDomeSampling {
        GpuDomeSampling {
            marginal: address,
            conditional: address + 4 * self.marginal.len() as u64,
            nodes: address
                + 4 * (self.marginal.len() + self.conditional.len()) as u64
                + 8 * self.guides.len() as u64,
            shape: self.shape,
            nodes_width: self.nodes_width,
            marginal_buckets: self.marginal_buckets,
            texels: match self.texel_offset {
                Some(offset) if texels != 0 => texels + 16 * offset,
                _ => 0,
            },
            width: self.width,
            height: self.height,
            integral: self.integral as f32,
            defensive: 0.0,
            sh: self.sh,
            ..Default::default()
        }
    }

    /// The probability the sampler gives texel (i, j): the same CDF differences the GPU takes.
    pub fn texel_probability(&self, i: u32, j: u32) -> f64 {
        let (i, j) = (i as usize, j as usize);
        let row = j * (self.width as usize + 1);
        let pm = self.marginal[j + 1] - self.marginal[j];
        let pc = self.conditional[row + i + 1] - self.conditional[row + i];
        f64::from(pm) * f64::from(pc)
    }
}

#[cfg(test)]
#[path = "dome_tests.rs"]
mod tests;
