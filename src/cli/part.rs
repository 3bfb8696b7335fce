//! `illum render --part K/N [--split samples|tiles]`: the job of a split render that a scheduler's
//! array index names (docs/farm.md). [`plan`] cuts an image into N jobs, each a sample range and a
//! pixel window, that `illum merge` puts back together bit for bit whatever N.
//!
//! - **samples** (the default): whole 256-sample film blocks (src/film/mod.rs), dealt out
//!   contiguously, so no job renders a block another job renders too. With more parts than blocks
//!   (N > ⌈spp/256⌉), a block cannot be shared without rendering it twice, so the parts of one
//!   block split its rows into bands instead (each block gets at least one part, the rest go to
//!   the blocks with the most samples per part).
//! - **tiles**: all samples of a grid of N windows, as square as the frame allows (c × r = N).

use crate::film::FILM_BLOCK;
use crate::film::Window;
use anyhow::{Result, bail};

/// How `--part` cuts the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Split {
    /// Sample ranges of whole 256-sample blocks (row bands of a block when N exceeds the blocks).
    Samples,
    /// A grid of N pixel windows, every sample.
    Tiles,
}

impl Split {
    pub fn name(self) -> &'static str {
        match self {
            Split::Samples => "samples",
            Split::Tiles => "tiles",
        }
    }
}

/// One job: the samples [A, B) of the pixels in `crop`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartJob {
    pub samples: (u32, u32),
    pub crop: Window,
}

/// Parses `K/N` (0 ≤ K < N), as given by a scheduler's array index.
pub fn parse_part(s: &str) -> std::result::Result<(u32, u32), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("{s:?} is not K/N (part K of N, K counted from 0)"))?;
    let num = |x: &str, what: &str| {
        x.trim()
            .parse::<u32>()
            .map_err(|_| format!("{what} {x:?} in {s:?} is not a whole number"))
    };
    let (k, n) = (num(k, "K")?, num(n, "N")?);
    if n == 0 {
        return Err(format!("N in {s:?} must be at least 1"));
    }
    if k >= n {
        return Err(format!(
            "K in {s:?} must be below N: parts are numbered 0 to {} (as $SLURM_ARRAY_TASK_ID \
             with --array=0-{} or $JOB_COMPLETION_INDEX)",
            n - 1,
            n - 1
        ));
    }
    Ok((k, n))
}

/// The N jobs of a `width`×`height` image of `spp` samples per pixel; job K is `plan(..)[K]`.
pub fn plan(n: u32, split: Split, spp: u32, width: u32, height: u32) -> Result<Vec<PartJob>> {
    if n == 0 || spp == 0 || width == 0 || height == 0 {
        bail!("cannot split a {width}x{height} image of {spp} spp into {n} parts");
    }
    crate::film::check_spp(spp).map_err(|e| anyhow::anyhow!("--spp: {e}"))?;
    let full = Window::full(width, height);
    match split {
        Split::Samples => {
            let blocks = spp.div_ceil(FILM_BLOCK);
            let block_end = |b: u32| (b * FILM_BLOCK).min(spp);
            if n <= blocks {
                return Ok((0..n)
                    .map(|k| {
                        let (b0, b1) = (
                            (u64::from(k) * u64::from(blocks) / u64::from(n)) as u32,
                            (u64::from(k + 1) * u64::from(blocks) / u64::from(n)) as u32,
                        );
                        PartJob {
                            samples: (block_end(b0), block_end(b1)),
                            crop: full,
                        }
                    })
                    .collect());
            }
            // More parts than blocks: each block gets one part, and every further part goes to
            // the block with the most samples per part so far (the first of equals).
            let mut per_block = vec![1u32; blocks as usize];
            for _ in blocks..n {
                let load = |b: usize| {
                    f64::from(block_end(b as u32 + 1) - block_end(b as u32))
                        / f64::from(per_block[b])
                };
                let mut best = 0;
                for b in 1..per_block.len() {
                    if load(b) > load(best) {
                        best = b;
                    }
                }
                per_block[best] += 1;
            }
            let most = *per_block.iter().max().expect("at least one block");
            if most > height {
                bail!(
                    "--part …/{n} --split samples: {spp} spp is {blocks} block(s) of 256 samples, \
                     so a block is split into {most} row bands, but the image has only {height} \
                     rows: use at most {} parts",
                    blocks * height
                );
            }
            let mut jobs = Vec::with_capacity(n as usize);
            for (b, &m) in per_block.iter().enumerate() {
                for j in 0..m {
                    jobs.push(PartJob {
                        samples: (block_end(b as u32), block_end(b as u32 + 1)),
                        crop: Window {
                            x0: 0,
                            y0: j * height / m,
                            x1: width,
                            y1: (j + 1) * height / m,
                        },
                    });
                }
            }
            Ok(jobs)
        }
        Split::Tiles => {
            // The c × r = N grid whose tiles are closest to square.
            let squareness = |c: u32| {
                let r = n / c;
                ((f64::from(width) / f64::from(c)) / (f64::from(height) / f64::from(r)))
                    .ln()
                    .abs()
            };
            let Some(c) = (1..=n)
                .filter(|c| n % c == 0 && *c <= width && n / c <= height)
                .min_by(|a, b| squareness(*a).total_cmp(&squareness(*b)))
            else {
                bail!(
                    "--part …/{n} --split tiles: no grid of {n} tiles (columns × rows = {n}) fits \
                     the {width}x{height} image: use fewer parts"
                );
            };
            let r = n / c;
            Ok((0..n)
                .map(|k| {
                    let (i, j) = (k % c, k / c);
                    PartJob {
                        samples: (0, spp),
                        crop: Window {
                            x0: (u64::from(i) * u64::from(width) / u64::from(c)) as u32,
                            y0: (u64::from(j) * u64::from(height) / u64::from(r)) as u32,
                            x1: (u64::from(i + 1) * u64::from(width) / u64::from(c)) as u32,
                            y1: (u64::from(j + 1) * u64::from(height) / u64::from(r)) as u32,
                        },
                    }
                })
                .collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every (pixel, sample) of the image is in exactly one job, and no two jobs share a film
    /// block of a pixel (so no block is rendered twice).
    fn check_cover(jobs: &[PartJob], spp: u32, w: u32, h: u32) {
        let mut count = vec![0u8; (w * h * spp) as usize];
        let mut block_owner = vec![usize::MAX; (w * h * spp.div_ceil(FILM_BLOCK)) as usize];
        for (k, j) in jobs.iter().enumerate() {
            assert!(j.samples.0 < j.samples.1, "job {k} {j:?} has no samples");
            assert!(
                j.crop.x0 < j.crop.x1 && j.crop.y0 < j.crop.y1,
                "job {k} {j:?} is empty"
            );
            for y in j.crop.y0..j.crop.y1 {
                for x in j.crop.x0..j.crop.x1 {
                    let p = y * w + x;
                    for s in j.samples.0..j.samples.1 {
                        count[(p * spp + s) as usize] += 1;
                        let b = (p * spp.div_ceil(FILM_BLOCK) + s / FILM_BLOCK) as usize;
                        assert!(
                            block_owner[b] == usize::MAX || block_owner[b] == k,
                            "jobs {} and {k} share block {} of pixel ({x}, {y})",
                            block_owner[b],
                            s / FILM_BLOCK
                        );
                        block_owner[b] = k;
                    }
                }
            }
        }
        assert!(count.iter().all(|&c| c == 1), "not an exact cover");
    }

    #[test]
    fn every_split_covers_every_sample_once_without_sharing_a_block() {
        for (spp, w, h) in [(16, 7, 5), (600, 13, 9), (1024, 4, 3), (257, 3, 8)] {
            for n in 1..=9 {
                for split in [Split::Samples, Split::Tiles] {
                    match plan(n, split, spp, w, h) {
                        Ok(jobs) => {
                            assert_eq!(jobs.len(), n as usize);
                            check_cover(&jobs, spp, w, h);
                        }
                        Err(e) => {
                            // Only a grid or band count that does not fit may fail.
                            assert!(e.to_string().contains("use "), "{e}");
                            assert!(split == Split::Tiles || n > h, "{n} {split:?}: {e}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn sample_parts_are_whole_blocks_while_there_are_enough() {
        let jobs = plan(3, Split::Samples, 1000, 8, 8).unwrap();
        let ranges: Vec<_> = jobs.iter().map(|j| j.samples).collect();
        assert_eq!(ranges, [(0, 256), (256, 512), (512, 1000)]);
        assert!(jobs.iter().all(|j| j.crop == Window::full(8, 8)));
        // 300 spp = a block of 256 and one of 44: three parts on the first, one on the second.
        let jobs = plan(4, Split::Samples, 300, 8, 9).unwrap();
        let got: Vec<_> = jobs
            .iter()
            .map(|j| (j.samples, j.crop.y0, j.crop.y1))
            .collect();
        assert_eq!(
            got,
            [
                ((0, 256), 0, 3),
                ((0, 256), 3, 6),
                ((0, 256), 6, 9),
                ((256, 300), 0, 9)
            ]
        );
    }

    #[test]
    fn tiles_are_as_square_as_the_frame_allows() {
        let jobs = plan(2, Split::Tiles, 16, 100, 50).unwrap();
        assert_eq!(
            jobs[1].crop,
            Window {
                x0: 50,
                y0: 0,
                x1: 100,
                y1: 50
            }
        );
        assert!(jobs.iter().all(|j| j.samples == (0, 16)));
        let jobs = plan(6, Split::Tiles, 16, 300, 200).unwrap();
        assert_eq!(
            jobs[1].crop,
            Window {
                x0: 100,
                y0: 0,
                x1: 200,
                y1: 100
            }
        );
        let e = plan(7, Split::Tiles, 16, 3, 5).unwrap_err().to_string();
        assert!(e.contains("3x5") && e.contains("7 tiles"), "{e}");
    }

    #[test]
    fn part_numbers_are_checked() {
        assert_eq!(parse_part("2/4"), Ok((2, 4)));
        assert!(parse_part("4/4").unwrap_err().contains("0 to 3"));
        assert!(parse_part("0/0").unwrap_err().contains("at least 1"));
        assert!(parse_part("x/4").unwrap_err().contains("\"x\""));
        assert!(parse_part("3").unwrap_err().contains("K/N"));
    }
}
