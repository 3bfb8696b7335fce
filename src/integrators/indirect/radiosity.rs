//! The radiosity cache (docs/techniques.md, "The radiosity cache"): the outgoing diffuse
//! radiance B = ρ/π·E of surfaces, cached in a world-space hashed grid for the indirect-diffuse
//! rays of the full integrator (glsl/indirect/indirect.glsl reads it; the update pass of
//! glsl/indirect/full.comp, the film pass's kernel, writes its samples).
//!
//! Why a hashed grid, and why its table is built on the host:
//! - A hashed grid needs only a hit's position and normal, so both trace paths and every shape
//!   kind (meshes, analytic shapes) share it; per-primitive grids would need per-triangle storage
//!   for 1M-triangle meshes and a parameterisation of spheres and disks.
//! - Cells come in power-of-two sizes; a lookup takes the size of its ray cone's width at the
//!   hit, so narrow specular rays read fine cells and wide diffuse ones coarse cells (the memo's
//!   three resolutions, continuous here). Lookups are jittered in the tangent plane by half a
//!   cell, trading the grid's seams for noise (Binder et al. 2019).
//! - The device writes update samples (records) to a buffer; the host averages them per cell in
//!   f64 in record order and builds the open-addressing table in sorted key order. So the cache,
//!   and every image rendered with it, is a deterministic function of the seed, with no float or
//!   64-bit atomics (stock Mesa 22's lavapipe has neither), and its memory is whatever the host
//!   allows: the table has a fixed number of slots, at most half of them used; the least
//!   recently updated cells are evicted first.
//!
//! Generations. A record's value reads the table of the previous generation (one bounce each:
//! a Jacobi iteration of the radiosity equation). Before the first sample, `warmup` rounds
//! each publish a generation; then the update samples that belong to sample indices [2^(g-1),
//! 2^g) form generation g + 1, published when sample 2^g begins. The table a sample sees is
//! thus a function of its index alone, so a render split into sample ranges or crops merges
//! bit-identically with the render in one piece (a job starting at sample A replays the updates
//! of indices below A; updates always cover the whole frame, whatever the crop).
//!
//! With `radiosity_refresh` off the warm-up's table serves every sample (no generation during
//! the render): what a render session does, since its passes run in the host's command buffers
//! and cannot hand records back to the host mid-frame (src/render/session.rs).
//!
//! Bias: a lag of ρ^(rounds) of the indirect light after `rounds` generations (the
//! warm-up takes enough that ρ_max^warmup ≤ 1e-3, at most 64), plus the blur of a cell, which
//! the cosine-weighted bounce that reads it integrates again. The cache never serves the camera
//! hit or direct light: reads happen only at the hit of a diffuse bounce, and only where the
//! segment is longer than the cell (else, or where the cell is empty, the bounce continues in
//! place, ended by Russian roulette: a miss costs time, not bias).

use crate::error::{Error, Result};
use crate::layout::*;
use crate::render::film_kernel::{interleaves_rows, tile_groups, tile_row_step};
use crate::vk::{Buffer, ComputePipeline, Context, MemoryLocation};
use ash::vk;
use std::cell::{self, RefCell};
use std::collections::HashMap;
use std::time::Instant;

/// Diffuse vertices per update path (records per path).
const VERTICES: u32 = 3;
/// Most cells (the table has twice as many slots) and most bytes of records per dispatch.
const MAX_SLOTS: u32 = 1 << 20;
const MAX_RECORD_BYTES: u64 = 8 << 20;
/// Update paths come one per BLOCK x BLOCK pixels, at most MAX_PATHS per sample index.
const BLOCK: u32 = 4;
const MAX_PATHS: u32 = 1 << 16;
/// Warm-up rounds take the lag below this fraction of the indirect light.
const WARMUP_LAG: f64 = 1e-3;
const MAX_WARMUP: u32 = 64;
/// Update indices of the warm-up rounds (apart from every sample index).
const WARMUP_INDEX: u32 = 0x8000_0000;
/// Update paths per warm-up round at least (small images get several rounds of indices), so
/// that every cell in use is refreshed by each generation.
const WARMUP_PATHS: u32 = 1024;
/// Cells not refreshed in this many generations are dropped: lookups there fall back to a
/// coarser level or a bounce in place, rather than to a value many bounces behind.
const MAX_AGE: u32 = 8;

/// The cache's layout for one image size and scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheShape {
    pub slots: u32,
    pub paths: u32,
    pub block: u32,
    /// Blocks across and down (paths = their product).
    pub blocks: [u32; 2],
    pub warmup: u32,
}

impl CacheShape {
    /// For a `width` x `height` image of a scene whose largest diffuse albedo is `max_albedo`.
    pub fn new(width: u32, height: u32, max_albedo: f32) -> CacheShape {
        let mut block = BLOCK;
        while width.div_ceil(block) * height.div_ceil(block) > MAX_PATHS {
            block += 1;
        }
        let blocks = [width.div_ceil(block), height.div_ceil(block)];
        let paths = blocks[0] * blocks[1];
        // Cells are at most half the slots; a generation's records name up to `keys` cells and
        // cells live MAX_AGE generations. Measured on scenes/interior.json at 320x240: 92k cells
        // for 29k keys per generation; 4x the keys as slots evicted live cells and cost 25% more
        // time in bounces done in place, 8x holds them all.
        let keys = u64::from(paths.max(WARMUP_PATHS)) * u64::from(VERTICES * RADIOSITY_RECORD_KEYS);
        let slots = (8 * keys)
            .next_power_of_two()
            .clamp(1 << 12, u64::from(MAX_SLOTS)) as u32;
        let rho = f64::from(max_albedo);
        let warmup = if rho <= 0.0 {
            1
        } else if rho >= 1.0 {
            MAX_WARMUP
        } else {
            (WARMUP_LAG.ln() / rho.ln())
                .ceil()
                .clamp(1.0, f64::from(MAX_WARMUP)) as u32
        };
        CacheShape {
            slots,
            paths,
            block,
            blocks,
            warmup,
        }
    }
}

#[derive(Clone, Copy, Default)]
struct Sum {
    value: [f64; 3],
    count: u32,
}

struct Cell {
    entry: RadiosityEntry,
    generation: u32,
}

struct State {
    seed: Option<u64>,
    /// Update indices done: [0, next_index).
    next_index: u32,
    /// The sample index from which the current table serves.
    table_from: u32,
    generation: u32,
    current: HashMap<[u32; 2], Sum>,
    cells: HashMap<[u32; 2], Cell>,
    records: Buffer,
    staging: Buffer,
    /// Cells that found no slot within RADIOSITY_PROBES of their hash, and cells evicted.
    dropped: u64,
    evicted: u64,
    update_paths: u64,
    update_seconds: f64,
    /// Of it, the warm-up's: what holds back the first sample.
    warmup_seconds: f64,
    /// Of it: the update dispatches (submitted and waited for), the host's averaging of their
    /// records, and building and uploading the tables.
    split_seconds: [f64; 3],
}

pub struct RadiosityCache {
    pub shape: CacheShape,
    table: Buffer,
    rounds_max: u32,
    /// Whether renders publish generations at samples 1, 2, 4, … (else the warm-up's table
    /// serves them all).
    refresh: cell::Cell<bool>,
    state: RefCell<State>,
}

fn record_bytes() -> u64 {
    std::mem::size_of::<RadiosityRecord>() as u64
}

impl RadiosityCache {
    pub fn new(ctx: &Context, shape: CacheShape) -> Result<Self> {
        let entry = std::mem::size_of::<RadiosityEntry>() as u64;
        let table_bytes = u64::from(shape.slots) * entry;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let table = ctx.create_buffer(
            "radiosity table",
            table_bytes,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let staging = ctx.create_buffer(
            "radiosity table (staging)",
            table_bytes,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let per_round = u64::from(shape.paths) * u64::from(VERTICES) * record_bytes();
        let rounds_max = (MAX_RECORD_BYTES / per_round).clamp(1, 256) as u32;
        let records = ctx.create_buffer(
            "radiosity records",
            per_round * u64::from(rounds_max),
            usage,
            MemoryLocation::GpuToCpu,
        )?;
        Ok(RadiosityCache {
            shape,
            table,
            rounds_max,
            refresh: cell::Cell::new(true),
            state: RefCell::new(State {
                seed: None,
                next_index: 0,
                table_from: 0,
                generation: 0,
                current: HashMap::new(),
                cells: HashMap::new(),
                records,
                staging,
                dropped: 0,
                evicted: 0,
                update_paths: 0,
                update_seconds: 0.0,
                warmup_seconds: 0.0,
                split_seconds: [0.0; 3],
            }),
        })
    }

    /// Points the frame constants at the table.
    pub fn configure(&self, frame: &mut Frame) {
        frame.radiosity_table = self.table.address;
        frame.radiosity_mask = self.shape.slots - 1;
    }

    /// Whether the next renders refresh the cache during their samples (RenderSettings'
    /// `integrator.radiosity_refresh`).
    pub fn set_refresh(&self, on: bool) {
        self.refresh.set(on);
    }

    /// Forgets every cell (a new render starts from an empty cache).
    pub fn reset(&self) {
        let mut st = self.state.borrow_mut();
        st.seed = None;
    }

    /// Brings the table to the one samples from `first` on see, and returns how many samples
    /// (at most `count`) see the same table. `kernel` is full.comp's, bound to a render.
    pub fn begin(
        &self,
        ctx: &Context,
        kernel: &ComputePipeline,
        seed: u64,
        first: u32,
        count: u32,
    ) -> Result<u32> {
        let t0 = Instant::now();
        let mut st = self.state.borrow_mut();
        if st.seed != Some(seed) || st.next_index > first {
            self.warm_up(ctx, kernel, &mut st, seed)?;
        }
        if !self.refresh.get() {
            // The warm-up's table serves every sample.
            st.update_seconds += t0.elapsed().as_secs_f64();
            return Ok(count);
        }
        while st.next_index < first {
            let i = st.next_index;
            if is_boundary(i) && st.table_from < i {
                self.publish(ctx, &mut st)?;
                st.table_from = i;
            }
            let rounds = (next_boundary(i).min(first) - i).min(self.rounds_max);
            self.update(ctx, kernel, &mut st, seed, i, rounds)?;
            st.next_index += rounds;
        }
        if is_boundary(first) && st.table_from < first {
            self.publish(ctx, &mut st)?;
            st.table_from = first;
        }
        st.update_seconds += t0.elapsed().as_secs_f64();
        Ok(count.min(next_boundary(first) - first))
    }

    fn warm_up(
        &self,
        ctx: &Context,
        kernel: &ComputePipeline,
        st: &mut State,
        seed: u64,
    ) -> Result<()> {
        st.seed = Some(seed);
        st.next_index = 0;
        st.table_from = 0;
        st.generation = 0;
        st.current.clear();
        st.cells.clear();
        st.dropped = 0;
        st.evicted = 0;
        st.update_paths = 0;
        st.update_seconds = 0.0;
        st.split_seconds = [0.0; 3];
        let t0 = Instant::now();
        self.publish(ctx, st)?; // the empty table
        let rounds = WARMUP_PATHS
            .div_ceil(self.shape.paths)
            .clamp(1, self.rounds_max);
        for round in 0..self.shape.warmup {
            self.update(ctx, kernel, st, seed, WARMUP_INDEX + round * rounds, rounds)?;
            self.publish(ctx, st)?;
        }
        st.warmup_seconds = t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Runs the update samples of indices [index, index + rounds) and adds their records to the
    /// generation being gathered.
    fn update(
        &self,
        ctx: &Context,
        kernel: &ComputePipeline,
        st: &mut State,
        seed: u64,
        index: u32,
        rounds: u32,
    ) -> Result<()> {
        let s = self.shape;
        // One invocation per block (x, y) and update index (z), in film-kernel workgroups.
        let blocks = [0, 0, s.blocks[0], s.blocks[1]];
        let [gx, gy, _] = tile_groups(blocks);
        let pc = FullPass {
            film: PassConstants {
                seed_lo: seed as u32,
                seed_hi: (seed >> 32) as u32,
                ..Default::default()
            },
            mode: FULL_PASS_UPDATE,
            pad0: 0,
            update: RadiosityPass {
                records: st.records.address,
                index,
                vertices: VERTICES,
                block: s.block,
                row_step: tile_row_step(interleaves_rows(ctx), blocks),
            },
        };
        let dispatched = Instant::now();
        ctx.one_shot(|cmd| {
            kernel.dispatch(cmd, bytemuck::bytes_of(&pc), [gx, gy, rounds]);
            // SAFETY: recording into the command buffer one_shot owns.
            unsafe {
                ctx.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &[vk::MemoryBarrier::default()
                        .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                        .dst_access_mask(vk::AccessFlags::HOST_READ)],
                    &[],
                    &[],
                )
            };
        })?;
        let gathered = Instant::now();
        st.split_seconds[0] += (gathered - dispatched).as_secs_f64();
        st.update_paths += u64::from(s.paths) * u64::from(rounds);
        let n = (s.paths * VERTICES * rounds) as usize;
        let State {
            records, current, ..
        } = st;
        let bytes = records
            .mapped()
            .ok_or_else(|| Error::Invalid("radiosity records are not host visible".into()))?;
        let records: &[RadiosityRecord] =
            bytemuck::cast_slice(&bytes[..n * std::mem::size_of::<RadiosityRecord>()]);
        for r in records.iter().filter(|r| r.valid != 0) {
            for (k, key) in r.keys.iter().enumerate() {
                // The coarsest level repeats when the footprint is near it: count a sample once.
                if r.keys[..k].contains(key) {
                    continue;
                }
                let sum = current.entry(*key).or_default();
                for c in 0..3 {
                    sum.value[c] += f64::from(r.value[c]);
                }
                sum.count += 1;
            }
        }
        st.split_seconds[1] += gathered.elapsed().as_secs_f64();
        Ok(())
    }

    /// Makes the gathered generation the table the kernels read.
    fn publish(&self, ctx: &Context, st: &mut State) -> Result<()> {
        let t0 = Instant::now();
        st.generation += 1;
        let generation = st.generation;
        let current = std::mem::take(&mut st.current);
        for (key, sum) in current {
            let n = f64::from(sum.count);
            st.cells.insert(
                key,
                Cell {
                    entry: RadiosityEntry {
                        value: sum.value.map(|v| (v / n) as f32),
                        count: sum.count,
                        key,
                        pad: [0; 2],
                    },
                    generation,
                },
            );
        }
        let before = st.cells.len();
        st.cells.retain(|_, c| c.generation + MAX_AGE > generation);
        st.evicted += (before - st.cells.len()) as u64;
        let slots = self.shape.slots as usize;
        let most = slots / 2;
        if st.cells.len() > most {
            // Least recently updated first; ties by key, so that the choice is deterministic.
            let mut order: Vec<(u32, [u32; 2])> =
                st.cells.iter().map(|(k, c)| (c.generation, *k)).collect();
            order.sort_unstable();
            for (_, k) in &order[..st.cells.len() - most] {
                st.cells.remove(k);
            }
            st.evicted += (order.len() - most) as u64;
        }
        let mut keys: Vec<[u32; 2]> = st.cells.keys().copied().collect();
        keys.sort_unstable();
        let mask = self.shape.slots - 1;
        let mut table = vec![RadiosityEntry::default(); slots];
        for key in keys {
            let home = key[0];
            let slot = (0..RADIOSITY_PROBES)
                .map(|i| (home.wrapping_add(i) & mask) as usize)
                .find(|&s| table[s].key[1] == 0);
            match slot {
                Some(s) => table[s] = st.cells[&key].entry,
                None => st.dropped += 1,
            }
        }
        let bytes: &[u8] = bytemuck::cast_slice(&table);
        st.staging
            .mapped()
            .ok_or_else(|| Error::Invalid("radiosity staging is not host visible".into()))?
            [..bytes.len()]
            .copy_from_slice(bytes);
        let staging = st.staging.buffer;
        ctx.one_shot(|cmd| {
            // SAFETY: both buffers are alive until the submission completes; the barrier orders
            // the copy before later kernels' reads.
            unsafe {
                ctx.device.cmd_copy_buffer(
                    cmd,
                    staging,
                    self.table.buffer,
                    &[vk::BufferCopy::default().size(bytes.len() as u64)],
                );
                ctx.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::DependencyFlags::empty(),
                    &[vk::MemoryBarrier::default()
                        .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                        .dst_access_mask(vk::AccessFlags::SHADER_READ)],
                    &[],
                    &[],
                )
            };
        })?;
        st.split_seconds[2] += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Figures for headers and summaries.
    pub fn report(&self) -> Vec<(String, String)> {
        let st = self.state.borrow();
        let s = self.shape;
        let table = u64::from(s.slots) * std::mem::size_of::<RadiosityEntry>() as u64;
        let records = st.records.size;
        let mib = |b: u64| b as f64 / f64::from(1 << 20);
        vec![
            (
                "radiosityCache".into(),
                format!(
                    "{} cells, {:.1} MiB ({} slots, {:.1} MiB table + staging, {:.1} MiB records)",
                    st.cells.len(),
                    mib(2 * table + records),
                    s.slots,
                    mib(2 * table),
                    mib(records),
                ),
            ),
            (
                "radiosityGenerations".into(),
                format!(
                    "{} ({} warm-up rounds)",
                    st.generation.saturating_sub(1),
                    s.warmup
                ),
            ),
            (
                "radiosityUpdates".into(),
                format!(
                    "{} paths of {VERTICES} vertices in {:.3} s ({:.3} s of warm-up before the first \
                     sample; {:.3} s in update dispatches, {:.3} s averaging their records, {:.3} s \
                     building and uploading tables)",
                    st.update_paths,
                    st.update_seconds,
                    st.warmup_seconds,
                    st.split_seconds[0],
                    st.split_seconds[1],
                    st.split_seconds[2]
                ),
            ),
            (
                "radiosityDropped".into(),
                format!("{} without a slot, {} evicted", st.dropped, st.evicted),
            ),
        ]
    }
}

/// Sample indices at which a new generation starts serving: 1, 2, 4, 8, ...
fn is_boundary(i: u32) -> bool {
    i.is_power_of_two()
}

/// The first boundary after sample index i.
fn next_boundary(i: u32) -> u32 {
    (i + 1).next_power_of_two()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generations_double() {
        assert_eq!(next_boundary(0), 1);
        assert_eq!(next_boundary(1), 2);
        assert_eq!(next_boundary(3), 4);
        assert_eq!(next_boundary(4), 8);
        assert!(is_boundary(256) && !is_boundary(0) && !is_boundary(3));
    }

    #[test]
    fn warm_up_takes_the_lag_below_its_bound() {
        let s = CacheShape::new(64, 48, 0.5);
        assert_eq!(s.warmup, 10);
        assert!(0.5f64.powi(s.warmup as i32) <= WARMUP_LAG);
        assert_eq!(CacheShape::new(64, 48, 0.9).warmup, MAX_WARMUP);
        assert_eq!(s.paths, 16 * 12);
        assert!(CacheShape::new(8000, 8000, 0.5).paths <= MAX_PATHS);
    }
}
