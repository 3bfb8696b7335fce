//! What every integrator's film kernel shares: its pipeline over film pixels (frame constants,
//! trace structure; the film and AOV planes by address), its binding to a render's buffers and
//! its dispatch over a tile, its workgroup rows interleaved on lavapipe.

use super::PreparedScene;
use crate::error::Result;
use crate::layout::*;
use crate::vk::{Buffer, ComputePipeline, Context};
use ash::vk;
use std::sync::atomic::{AtomicU64, Ordering};

/// A kernel over film pixels: its pipeline (frame constants and the trace structure by
/// descriptor, the scene's feature switches and the settings' own) and the device addresses of
/// the film and AOV planes it is bound to, which its dispatches pass in PassConstants
/// (`film_address`, `aovs_address`): lavapipe compiles a storage buffer's access at a per-lane
/// index into a branch per lane and component, which cost the `full` kernel a quarter of its
/// compile time (docs/performance-kernels.md, "The film by address").
pub struct FilmKernel {
    pub pipeline: ComputePipeline,
    /// Whether the kernel adds to AOV planes (Integrator::aov_planes).
    aovs: bool,
    /// The bound film's and AOV planes' addresses (0: not bound).
    film: [AtomicU64; 2],
}

impl FilmKernel {
    /// The kernel `name` (its ray-query and BVH variants), taking `push_size` bytes of push
    /// constants (PassConstants, or a struct that begins with them).
    pub fn new(
        ctx: &Context,
        scene: &PreparedScene,
        features: u32,
        name: &str,
        (rq, bvh): (&'static [u8], &'static [u8]),
        aovs: bool,
        push_size: usize,
    ) -> Result<FilmKernel> {
        let mut bindings = vec![(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER)];
        bindings.extend(scene.trace.bindings());
        let pipeline = ComputePipeline::new(
            ctx,
            name,
            scene.trace.select(rq, bvh),
            &bindings,
            push_size as u32,
            &[scene.gpu.features | features, scene.gpu.flat_kinds],
        )?;
        scene.trace.bind(&pipeline);
        Ok(FilmKernel {
            pipeline,
            aovs,
            film: [AtomicU64::new(0), AtomicU64::new(0)],
        })
    }

    /// Points the kernel at a render's frame constants, film and AOV planes.
    pub fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        debug_assert!(
            !self.aovs || aovs.is_some(),
            "a kernel that adds to AOV planes needs them bound"
        );
        self.pipeline
            .bind_buffer(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER, frame);
        self.film[0].store(film.address, Ordering::Relaxed);
        let aovs = if self.aovs {
            aovs.map_or(0, |a| a.address)
        } else {
            0
        };
        self.film[1].store(aovs, Ordering::Relaxed);
    }

    /// `pass` with the bound film's addresses.
    pub fn pass(&self, pass: &PassConstants) -> PassConstants {
        PassConstants {
            film_address: self.film[0].load(Ordering::Relaxed),
            aovs_address: self.film[1].load(Ordering::Relaxed),
            ..*pass
        }
    }

    /// Dispatches the kernel over the pixels of `pass.tile`.
    pub fn dispatch_tile(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        let pass = self.pass(pass);
        self.pipeline
            .dispatch(cmd, bytemuck::bytes_of(&pass), tile_groups(pass.tile));
    }
}

/// The workgroups of a film kernel over the pixels of `tile` (x0, y0, width, height).
pub fn tile_groups(tile: [u32; 4]) -> [u32; 3] {
    [
        tile[2].div_ceil(WORKGROUP_X),
        tile[3].div_ceil(WORKGROUP_Y),
        1,
    ]
}

/// Whether a device runs a dispatch's workgroups in equal contiguous ranges, one per thread
/// (lavapipe): its dispatches then interleave their rows (PassConstants.row_step), else the
/// thread with the cheaper rows idles (measured in docs/performance-kernels.md, "Rows
/// interleaved between lavapipe's threads"). Other drivers schedule workgroups as they go.
pub fn interleaves_rows(ctx: &Context) -> bool {
    ctx.0.info.driver_id == vk::DriverId::MESA_LLVMPIPE
}

/// PassConstants.row_step (or RadiosityPass's) of a dispatch over `tile` (its workgroups
/// [`tile_groups`]): rows interleaved where the device runs workgroups in contiguous ranges
/// ([`interleaves_rows`]), else 0 (in order).
pub fn tile_row_step(interleave: bool, tile: [u32; 4]) -> u32 {
    if interleave {
        row_step(tile_groups(tile)[1])
    } else {
        0
    }
}

/// The step between the tile rows that consecutive workgroup rows of a dispatch cover (see
/// PassConstants.row_step): the integer nearest rows / phi coprime to `rows`, so that any run of
/// consecutive workgroup rows spreads over the tile like a golden-ratio sequence.
pub fn row_step(rows: u32) -> u32 {
    let gcd = |mut a: u32, mut b: u32| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let mut s = ((f64::from(rows) * 0.618_034).round() as u32).max(1);
    while gcd(s, rows) != 1 {
        s += 1;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gcd(a: u32, b: u32) -> u32 {
        if b == 0 { a } else { gcd(b, a % b) }
    }

    /// The interleaved rows are a permutation, and each of T equal contiguous ranges of workgroup
    /// rows (lavapipe's split between T threads) covers every half and quarter of the tile in
    /// proportion, within 1 + log2(rows) rows: the discrepancy bound of the golden-ratio sequence
    /// the step follows (it grows as log N).
    #[test]
    fn interleaved_rows_spread_each_thread_over_the_tile() {
        for rows in 1..=512u32 {
            let s = row_step(rows);
            assert_eq!(gcd(s, rows), 1, "rows {rows}: step {s}");
            let order: Vec<u32> = (0..rows).map(|r| r * s % rows).collect();
            let mut seen = order.clone();
            seen.sort_unstable();
            assert!(
                seen.iter().copied().eq(0..rows),
                "rows {rows}: not a permutation"
            );
            let bound = 1.0 + f64::from(rows).log2();
            for threads in [2u32, 4, 8] {
                for t in 0..threads {
                    let part =
                        &order[(t * rows / threads) as usize..((t + 1) * rows / threads) as usize];
                    for q in [2u32, 4] {
                        for k in 0..q {
                            let inside = part.iter().filter(|&&r| r * q / rows == k).count() as f64;
                            let dev = (inside - part.len() as f64 / f64::from(q)).abs();
                            assert!(
                                dev <= bound,
                                "rows {rows}, {threads} threads, range {t}, {q}ths {k}: {dev}"
                            );
                        }
                    }
                }
            }
        }
    }
}
