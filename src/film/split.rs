//! Which pixels split their samples into two camera sequences (Frame.witness; glsl/film/film.glsl,
//! `film_samples`), the half-buffers the error estimate is made of (crate::metrics).
//!
//! Two independent sequences are what an unbiased error estimate needs, but a pixel whose samples
//! alternate between them is stratified over half its samples only, which costs 1.0–1.6× of
//! relMSE at equal samples (docs/performance-sampling.md, "What the half-buffer split costs").
//! So in an image of at least [`WITNESS_BLOCKS_MIN`] blocks of 8 × 8 pixels (workgroups, so that no
//! SIMD group holds witnesses and other pixels, which take unequal sample counts), only one block
//! in [`WITNESS_PERIOD`] is a witness: its pixels take both sequences' samples (twice the others'),
//! the other pixels the first sequence's alone. A witness's two halves are then two independent
//! renders of what every other pixel renders, and their difference estimates the error of all
//! of them. Smaller images (the pilots, tests) and adaptive sampling split every pixel's samples,
//! as before. The rule is glsl/film/film.glsl's `film_samples`, with the constants of
//! glsl/shared/layout.glsl.

use crate::layout::{WITNESS_ROW_STEP, WORKGROUP_X, WORKGROUP_Y};

/// One block in this many is a witness (in images of [`WITNESS_BLOCKS_MIN`] blocks or more).
pub const WITNESS_PERIOD: u32 = 16;
/// The fewest blocks an image has for witness blocks: 32 witnesses (2048 pixels) at least.
pub const WITNESS_BLOCKS_MIN: u32 = 32 * WITNESS_PERIOD;

/// Frame.witness: the witness period (1: every pixel split) and offset. The default: every pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Split {
    period: u32,
    offset: u32,
}

impl Split {
    /// Every pixel alternates between the two sequences (its count is the pass's).
    pub const ALL: Split = Split {
        period: 1,
        offset: 0,
    };

    /// The split of an image of `width` × `height` pixels rendered with `seed`: witness blocks
    /// where the image is large enough, their offset drawn from the seed (each block is a witness
    /// with probability 1/16 over seeds, so that the estimate is unbiased for the whole image).
    pub fn of_image(width: u32, height: u32, seed: u64) -> Split {
        let blocks = width.div_ceil(WORKGROUP_X) as u64 * height.div_ceil(WORKGROUP_Y) as u64;
        if blocks < u64::from(WITNESS_BLOCKS_MIN) {
            return Split::ALL;
        }
        let h = (seed ^ 0x9e37_79b9_7f4a_7c15).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        Split {
            period: WITNESS_PERIOD,
            offset: ((h ^ (h >> 31)) % u64::from(WITNESS_PERIOD)) as u32,
        }
    }

    /// The split a blocking render of `width` × `height` pixels with `seed` takes: witness
    /// blocks ([`Split::of_image`]) unless adaptive sampling sets each pixel's count from the
    /// half-buffers of its pilot (then every pixel splits).
    pub fn of_render(width: u32, height: u32, seed: u64, adaptive: bool) -> Split {
        if adaptive {
            Split::ALL
        } else {
            Split::of_image(width, height, seed)
        }
    }

    /// The Frame.witness word.
    pub fn word(self) -> u32 {
        self.period | self.offset << 16
    }

    /// The split of a Frame.witness word ([`Split::word`]).
    pub fn from_word(word: u32) -> Split {
        Split {
            period: (word & 0xffff).max(1),
            offset: word >> 16,
        }
    }

    /// Whether pixel (x, y) of the image splits its samples.
    pub fn splits(self, x: u32, y: u32) -> bool {
        if self.period <= 1 {
            return true;
        }
        let (bx, by) = (x / WORKGROUP_X, y / WORKGROUP_Y);
        (bx + WITNESS_ROW_STEP * by + self.offset) % self.period == 0
    }

    /// Whether only witness pixels split (the others take one sequence).
    pub fn witnesses(self) -> bool {
        self.period > 1
    }

    /// The samples each pixel of a window at (x0, y0), `width` × `height` (row-major), takes in
    /// a render of `spp` samples a pixel: twice that at witness pixels.
    pub fn counts(self, x0: u32, y0: u32, width: u32, height: u32, spp: u32) -> Vec<u32> {
        let witnesses = self.witnesses();
        self.window(x0, y0, width, height)
            .into_iter()
            .map(|s| if witnesses && s { 2 * spp } else { spp })
            .collect()
    }

    /// Each pixel's flag of a window at (x0, y0), `width` × `height`, row-major.
    pub fn window(self, x0: u32, y0: u32, width: u32, height: u32) -> Vec<bool> {
        (y0..y0 + height)
            .flat_map(|y| (x0..x0 + width).map(move |x| self.splits(x, y)))
            .collect()
    }
}

impl Default for Split {
    fn default() -> Split {
        Split::ALL
    }
}
