//! The kernel profile: in a build whose kernels time their regions (`ILLUM_PROFILE_KERNELS=1
//! cargo build --release`, glsl/shared/profile.glsl), every render prints the share of its
//! kernels' time each region of their source took. For measurement only: the clock reads cost
//! time of their own (docs/performance-kernels.md, "Kernel regions").

use crate::error::Result;
use crate::layout::*;
use crate::vk::{Buffer, Context};
use ash::vk;

/// The regions' names, by their index (glsl/shared/layout.glsl numbers them).
const REGIONS: &[(u32, &str)] = &[
    (PROF_CAMERA_RAY, "camera ray"),
    (PROF_CAMERA_TRACE, "camera trace"),
    (PROF_CAMERA_SHADE, "camera hit shading and AOVs"),
    (PROF_DIRECT_PLAN, "direct: plan"),
    (PROF_LIGHT_SAMPLE, "direct: light samples"),
    (PROF_BRDF_SAMPLE, "direct: BRDF samples"),
    (PROF_SHADOW_TRACE, "direct: shadow traversal"),
    (
        PROF_DIRECT_LOOP,
        "direct: sample step, and waiting for the group's other lanes",
    ),
    (PROF_FILM, "film"),
    (PROF_BOUNCE_TRACE, "bounce: trace"),
    (PROF_BOUNCE_SHADE, "bounce: hit shading"),
    (PROF_BOUNCE, "bounce: continuation"),
    (PROF_OTHER, "other"),
    (PROF_DIRECT_OPEN, "direct: opening a group"),
    (PROF_DIRECT_FLUSH, "direct: resampling flush"),
    (
        PROF_DIRECT_CANDIDATES,
        "direct: candidates (closing groups, joining the resampling)",
    ),
];

/// The region of empty spans: what one mark costs.
const EMPTY: usize = PROF_EMPTY as usize;

/// The buffer's words for `slots` film slots, all zero.
fn zeros(slots: usize) -> Vec<u64> {
    vec![0; slots * 2 * PROFILE_REGIONS as usize]
}

/// Per film slot, one uint64 per region of time, then one of marks, summed over the kernels'
/// invocations.
pub struct Profile {
    buffer: Buffer,
    slots: usize,
}

impl Profile {
    /// The buffer for `slots` film slots, or None when the kernels do not time their regions.
    pub fn new(ctx: &Context, slots: usize) -> Result<Option<Profile>> {
        if !crate::shaders::PROFILED {
            return Ok(None);
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let buffer = ctx.upload("kernel profile", &zeros(slots), usage)?;
        Ok(Some(Profile { buffer, slots }))
    }

    pub fn address(&self) -> u64 {
        self.buffer.address
    }

    /// Starts the sums afresh (each of a pilot's candidates, each restart of a view).
    pub fn clear(&self, ctx: &Context) -> Result<()> {
        Ok(ctx.write(&self.buffer, 0, &zeros(self.slots))?)
    }

    /// Each region's share of the time summed so far, largest first, after taking off what its
    /// marks cost (the empty spans' time per mark).
    pub fn report(&self, ctx: &Context) -> Result<String> {
        let n = PROFILE_REGIONS as usize;
        let v: Vec<u64> = ctx.download(&self.buffer, self.slots * 2 * n)?;
        let (mut time, mut marks) = (vec![0f64; n], vec![0f64; n]);
        for slot in v.chunks(2 * n) {
            for r in 0..n {
                time[r] += slot[r] as f64;
                marks[r] += slot[n + r] as f64;
            }
        }
        let per_mark = time[EMPTY] / marks[EMPTY].max(1.0);
        let raw: f64 = time
            .iter()
            .enumerate()
            .filter(|r| r.0 != EMPTY)
            .map(|r| r.1)
            .sum();
        let net: Vec<(usize, f64)> = (0..n)
            .filter(|&r| r != EMPTY && marks[r] > 0.0)
            .map(|r| (r, (time[r] - per_mark * marks[r]).max(0.0)))
            .collect();
        let total: f64 = net.iter().map(|r| r.1).sum();
        let mut rows = net;
        rows.sort_by(|a, b| b.1.total_cmp(&a.1));
        let mut out = format!(
            "illum: kernel profile, each region's share of the kernels' time net of its clock reads \
             ({:.0} ns a read; reads were {:.0}% of the measured time):",
            per_mark,
            100.0 * (raw - total) / raw.max(1.0)
        );
        for (r, t) in rows {
            let name = REGIONS
                .iter()
                .find(|(i, _)| *i as usize == r)
                .map_or("?", |(_, name)| name);
            out.push_str(&format!(
                "\n  {:>5.1}%  {name} ({:.1} marks per invocation)",
                100.0 * t / total.max(1.0),
                marks[r] / self.slots as f64
            ));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_region_has_one_name_and_a_slot() {
        let mut seen = std::collections::HashSet::new();
        for &(r, name) in REGIONS {
            assert!(
                r < PROFILE_REGIONS && r as usize != EMPTY,
                "{name}: region {r}"
            );
            assert!(seen.insert(r), "{name}: region {r} named twice");
        }
        // Every index up to the empty spans' is named, and the empty spans' is the last.
        assert_eq!(seen.len(), EMPTY);
        assert_eq!(PROFILE_REGIONS as usize, EMPTY + 1);
    }
}
