//! The direct-lighting sample allocation, measured on the scene before it renders
//! (docs/allocation.md): a pilot renders a small image of the same camera under candidate
//! allocations and keeps the one with the least estimated relMSE × cost, cost in rays per camera
//! sample plus one (the camera sample's own shading). The candidates move one setting at a time
//! from the integrator's counts: how light samples pick lights (a loop over every light or the
//! light tree, where the scene has a tree and few enough lights for the loop), the floor under
//! small lights (1, the course's share rule, or N_max), N_max, the BRDF samples per lobe, a
//! textured dome's samples and diffuse MIS.
//!
//! The pilot is deterministic (its own seed, a size that follows the image and the spp, never the
//! job's range or crop, and costs counted in rays, not seconds), so every job of a split render
//! decides the same allocation and the jobs merge bit-identically. Its samples are left out of
//! the image, so the allocation is independent of the image's samples and the image stays
//! unbiased: every allocation is an unbiased estimator (MIS weights use the counts taken).

use super::blocking::Blocking;
use super::{PreparedScene, RenderSettings, Renderer};
use crate::error::Result;
use crate::layout::{
    DIRECT_LOOP_LIGHTS, Frame, INTEGRATOR_DIFFUSE_MIS, LIGHT_SELECT_LOOP, LIGHT_SELECT_TREE,
    TECHNIQUE_MIS,
};
use crate::scene::Camera;
use std::time::Instant;

/// The pilot's samples per pixel: a power of two, so its half-buffers split evenly.
pub const PILOT_SPP: u32 = 16;
/// Most pixels of the pilot's image, and fewest (a smaller one measures too little: the render
/// keeps the integrator's counts).
pub const PILOT_PIXELS: u64 = 6912;
pub const PILOT_MIN_PIXELS: u64 = 1024;
/// A spp render spends at most 1/PILOT_SHARE of its camera samples on all its candidates.
pub const PILOT_SHARE: u64 = 16;
/// Most candidates a pilot renders.
pub const MAX_CANDIDATES: u64 = 10;
/// Under a time budget, the fewest candidates the pilot's time must afford at the first one's
/// rate (else it tries none).
pub const LEAST_CANDIDATES: f64 = 4.0;
/// A time-budgeted render gives its pilot this share of the budget: the first candidate, at
/// PILOT_MIN_PIXELS, measures the rate that sizes the others (none when the share would not
/// afford LEAST_CANDIDATES at that rate), and the search stops when the share is spent.
pub const PILOT_TIME_SHARE: f64 = 0.06;
/// The loop or the tree (step 0) replaces the other only if its estimated cost × relMSE is
/// below this share of the other's as well as Z_SELECTION standard errors below it. The count
/// moves have no such margin: two standard errors of the paired difference decide them. The
/// pilot's pixels dilute what varies within an image pixel into every candidate alike, which
/// pulls a true gain towards 1, not past it; with a margin of 0.85 the pilot kept moves of
/// 0.86-0.88 that were worth 1.13-1.35x at equal time (docs/allocation.md, stop 55).
pub const SELECTION_MARGIN: f64 = 0.85;
/// The pilot's seed, the same for every seed of the image: the allocation is a property of the
/// scene and settings, not of one render's random numbers.
pub const PILOT_SEED: u64 = 0xA110_CA7E_5EED_0001;

/// How the direct-lighting sample counts are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AllocationMode {
    /// The integrator's counts as given (the course's rule: each light its share of N_max).
    #[default]
    Fixed,
    /// Measured by a pilot before the render (this module).
    Auto,
}

impl AllocationMode {
    pub fn name(self) -> &'static str {
        match self {
            AllocationMode::Fixed => "fixed",
            AllocationMode::Auto => "auto",
        }
    }
}

impl std::str::FromStr for AllocationMode {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "fixed" => Ok(AllocationMode::Fixed),
            "auto" => Ok(AllocationMode::Auto),
            _ => Err(format!("unknown allocation {s:?} (expected auto or fixed)")),
        }
    }
}

/// Direct lighting's sample counts (Frame.light_samples, brdf_samples, dome_samples,
/// light_floor) and how its light samples pick lights (Frame.light_select).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counts {
    /// Light samples pick finite lights from the light tree, N_max of them in all
    /// (LIGHT_SELECT_TREE); else every light is looped over.
    pub tree: bool,
    /// N_max: most light samples per looped light (with the tree: picks per camera sample).
    pub light_samples: u32,
    /// BRDF samples per lobe.
    pub brdf_samples: u32,
    /// A textured dome's samples per N_max.
    pub dome_samples: u32,
    /// Fewest samples per looped light (1: the share rule alone).
    pub light_floor: u32,
    /// The diffuse lobe also by cosine-sampled BRDF samples under MIS (INTEGRATOR_DIFFUSE_MIS).
    pub diffuse_mis: bool,
}

impl Counts {
    /// The counts the frame holds (an integrator has configured it).
    pub fn of(frame: &Frame) -> Counts {
        Counts {
            tree: frame.light_select == LIGHT_SELECT_TREE,
            light_samples: frame.light_samples,
            brdf_samples: frame.brdf_samples,
            dome_samples: frame.dome_samples,
            light_floor: frame.light_floor.max(1),
            diffuse_mis: frame.integrator_flags & INTEGRATOR_DIFFUSE_MIS != 0,
        }
    }

    pub fn apply(&self, frame: &mut Frame) {
        // Only between the loop and the tree (a scan asked for is kept).
        if self.tree && frame.light_tree != 0 {
            frame.light_select = LIGHT_SELECT_TREE;
        } else if frame.light_select == LIGHT_SELECT_TREE {
            frame.light_select = LIGHT_SELECT_LOOP;
        }
        frame.light_samples = self.light_samples;
        frame.brdf_samples = self.brdf_samples;
        frame.dome_samples = self.dome_samples;
        frame.light_floor = self.light_floor.clamp(1, self.light_samples);
        frame.integrator_flags &= !INTEGRATOR_DIFFUSE_MIS;
        if self.diffuse_mis {
            frame.integrator_flags |= INTEGRATOR_DIFFUSE_MIS;
        }
    }

    pub fn describe(&self) -> String {
        format!(
            "light_selection={} light_samples={} light_floor={} brdf_samples={} dome_samples={} \
             diffuse_mis={}",
            if self.tree { "tree" } else { "loop" },
            self.light_samples,
            self.light_floor,
            self.brdf_samples,
            self.dome_samples,
            if self.diffuse_mis { "on" } else { "off" }
        )
    }
}

/// What the pilot decided, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct Allocation {
    pub counts: Counts,
    /// How they were chosen, for the header: deterministic (no times), so that the jobs of a
    /// split render write the same.
    pub how: String,
}

/// One candidate's pilot: each pixel's estimated relMSE (NaN: left out) and the rays per
/// camera sample.
#[derive(Clone, Debug)]
struct Measured {
    pixels: Vec<f64>,
    rays: f64,
}

impl Measured {
    /// Its cost and `other`'s over the pixels both measured, cost being relMSE × time, time as
    /// rays per camera sample plus one for the camera sample's shading; and the standard error
    /// of their difference, pixel by pixel (the candidates share the pilot's seed, so their
    /// pixels' errors go together: the paired difference is far steadier than either).
    fn against(&self, other: &Measured) -> (f64, f64, f64) {
        let (a, b) = (self.rays + 1.0, other.rays + 1.0);
        let (mut n, mut sa, mut sb, mut sd2) = (0.0, 0.0, 0.0, 0.0);
        for (x, y) in self.pixels.iter().zip(&other.pixels) {
            if x.is_nan() || y.is_nan() {
                continue;
            }
            let d = x * a - y * b;
            n += 1.0;
            sa += x * a;
            sb += y * b;
            sd2 += d * d;
        }
        if n < 2.0 {
            return (f64::NAN, f64::NAN, f64::NAN);
        }
        let md = (sa - sb) / n;
        let var = ((sd2 - n * md * md) / (n - 1.0)).max(0.0);
        (sa / n, sb / n, (var / n).sqrt())
    }

    /// Whether it costs less than `margin` × `best`'s and by more than `z` standard errors of
    /// their paired difference: a move the pilot's noise does not explain.
    fn beats(&self, best: &Measured, z: f64, margin: f64) -> bool {
        let (mine, theirs, se) = self.against(best);
        mine < margin * theirs && theirs - mine > z * se
    }
}

/// Standard errors of the paired difference a candidate's gain must exceed (the pixels'
/// estimates are independent of each other; their heavy tails make this a floor, not a bound).
pub const Z: f64 = 2.0;
/// The same for the loop against the tree (step 0): one standard error (84% one-sided). They
/// are estimators of different kinds whose costs differ 3–60× on the benchmark scenes
/// (docs/allocation.md), so their gains come mostly from few pixels and rarely reach two
/// standard errors; and the loop up to DIRECT_LOOP_LIGHTS lights is a rule with no better claim
/// to stand where the pilot cannot tell.
pub const Z_SELECTION: f64 = 1.0;

/// The pilot's image size for a render of `settings` at `width` x `height` (None: too small a
/// render for a pilot): at most PILOT_PIXELS, at most 1/(PILOT_SHARE × MAX_CANDIDATES) of the
/// render's camera samples at PILOT_SPP (a spp render; a time-budgeted one starts at
/// PILOT_MIN_PIXELS), the camera's aspect kept.
pub fn pilot_size(settings: &RenderSettings, width: u32, height: u32) -> Option<(u32, u32)> {
    let pixels = u64::from(width) * u64::from(height);
    let mut most = PILOT_PIXELS.min(pixels);
    if settings.time.is_some() {
        // Sized again once the first candidate has measured the rate (Renderer::pilot).
        most = most.min(PILOT_MIN_PIXELS);
    } else {
        let samples = pixels * u64::from(settings.spp);
        most = most.min(samples / (PILOT_SHARE * MAX_CANDIDATES * u64::from(PILOT_SPP)));
    }
    if most < PILOT_MIN_PIXELS {
        return None;
    }
    Some(sized(most as f64, width, height))
}

/// An image of about `pixels` pixels (fewer, never more) with the aspect of `width` x `height`,
/// and no larger.
fn sized(pixels: f64, width: u32, height: u32) -> (u32, u32) {
    let aspect = f64::from(width) / f64::from(height);
    let w = ((pixels * aspect).sqrt().floor() as u32).clamp(1, width);
    let h = ((pixels / f64::from(w)).floor() as u32).clamp(1, height);
    (w, h)
}

/// `v` halved and doubled, those within 1..=`most`.
fn halved_doubled(v: u32, most: u32) -> impl Iterator<Item = u32> {
    [v / 2, v * 2]
        .into_iter()
        .filter(move |n| (1..=most).contains(n) && *n != v)
}

/// The candidates after `best`, one setting moved at a time: the loop or the tree, the floor,
/// then N_max down and up, the BRDF samples down and up, a textured dome's samples down and up,
/// diffuse MIS (the pilot goes on the way a move won, one halving or doubling at a time).
fn neighbours(step: usize, best: Counts, scene: Scope) -> Vec<Counts> {
    let c = best;
    let Scope {
        textured_dome,
        finite_lights,
        selection,
        mis,
    } = scene;
    match step {
        0 if selection => vec![Counts { tree: !c.tree, ..c }],
        // The floor is for looped lights: with the tree only the infinite ones are looped.
        1 if finite_lights && !c.tree && c.light_floor < c.light_samples => vec![Counts {
            light_floor: c.light_samples,
            ..c
        }],
        2 => {
            let floor_at_max = c.light_floor >= c.light_samples;
            halved_doubled(c.light_samples, 16)
                .map(|n| Counts {
                    light_samples: n,
                    light_floor: if floor_at_max {
                        n
                    } else {
                        c.light_floor.min(n)
                    },
                    ..c
                })
                .collect()
        }
        3 => halved_doubled(c.brdf_samples, 8)
            .map(|n| Counts {
                brdf_samples: n,
                ..c
            })
            .collect(),
        4 if textured_dome => halved_doubled(c.dome_samples, 16)
            .map(|n| Counts {
                dome_samples: n,
                ..c
            })
            .collect(),
        5 if mis => vec![Counts {
            diffuse_mis: !c.diffuse_mis,
            ..c
        }],
        _ => Vec::new(),
    }
}

/// Whether a loop over the scene's lights is affordable (up to DIRECT_LOOP_LIGHTS): the `auto`
/// light selection loops there, and the pilot may measure the tree against it.
pub fn loop_affordable(frame: &Frame) -> bool {
    frame.light_count <= DIRECT_LOOP_LIGHTS
}

/// What a pilot found.
struct Pilot {
    /// The best counts.
    counts: Counts,
    /// Candidates rendered.
    tried: u32,
    /// Whether the time budget cut the search short.
    stopped: bool,
    /// Wall seconds of the candidates' renders (the set-up, kernel compilation included, is the
    /// render's).
    seconds: f64,
    /// Its image size, which a time budget may have changed.
    size: (u32, u32),
}

/// What of the scene decides which candidates mean anything.
#[derive(Clone, Copy, Debug)]
struct Scope {
    /// A dome with sampling tables (dome_samples applies).
    textured_dome: bool,
    /// A light that is not infinite (the floor applies).
    finite_lights: bool,
    /// A light tree, and few enough lights for the loop (DIRECT_LOOP_LIGHTS): both selections
    /// can run.
    selection: bool,
    /// Direct lighting by MIS (diffuse MIS applies).
    mis: bool,
}

pub const STEPS: usize = 6;

/// The setting step `step` moves.
fn key(step: usize, c: &Counts) -> u32 {
    match step {
        0 => u32::from(c.tree),
        1 => c.light_floor,
        2 => c.light_samples,
        3 => c.brdf_samples,
        4 => c.dome_samples,
        _ => u32::from(c.diffuse_mis),
    }
}

/// Steps whose one move is a switch (no line search along them).
fn switch(step: usize) -> bool {
    matches!(step, 0 | 1 | 5)
}

impl Renderer {
    /// The settings a render of `prepared` through `camera` runs with: `settings` with the
    /// allocation decided when its integrator asks for one to be measured (and none is decided
    /// yet). Returns the pilot's wall seconds too (0 without one).
    pub fn decide_allocation(
        &self,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<(RenderSettings, f64)> {
        let mut out = settings.clone();
        if settings.allocation.is_some() {
            return Ok((out, 0.0));
        }
        if !settings.integrator.measured_allocation() {
            return Ok((out, 0.0));
        }
        // The integrator's own counts: where the search starts.
        let scene = &prepared.gpu.frame;
        let mut frame = *scene;
        settings.integrator.configure(&mut frame);
        let start = Counts::of(&frame);
        let scope = Scope {
            textured_dome: scene.dome_sampling != 0,
            finite_lights: scene.light_count > scene.infinite_count,
            selection: scene.light_tree != 0
                && loop_affordable(scene)
                && matches!(frame.light_select, LIGHT_SELECT_LOOP | LIGHT_SELECT_TREE),
            mis: frame.technique == TECHNIQUE_MIS,
        };
        let Some((w, h)) = pilot_size(settings, camera.width, camera.height) else {
            out.allocation = Some(Allocation {
                counts: start,
                how: "fixed: the render is too small for a pilot".into(),
            });
            return Ok((out, 0.0));
        };
        let p = self.pilot(prepared, camera, settings, start, scope, (w, h))?;
        let (w, h) = p.size;
        let how = format!(
            "measured: a pilot of {} candidates at {w}x{h}, {PILOT_SPP} spp{}",
            p.tried,
            if p.stopped {
                ", cut short by the time budget"
            } else {
                ""
            }
        );
        out.allocation = Some(Allocation {
            counts: p.counts,
            how,
        });
        Ok((out, p.seconds))
    }

    /// Renders the candidates from `start` (those `scope` gives meaning) at `size`.
    fn pilot(
        &self,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
        start: Counts,
        scope: Scope,
        size: (u32, u32),
    ) -> Result<Pilot> {
        let ctx = self.context();
        let mut pilot_camera = camera.clone();
        (pilot_camera.width, pilot_camera.height) = size;
        let mut s = RenderSettings {
            spp: PILOT_SPP,
            time: None,
            seed: PILOT_SEED,
            reference: None,
            evaluate_passes: false,
            inject_non_finite: 0,
            samples: None,
            crop: None,
            adaptive: None,
            allocation: Some(Allocation {
                counts: start,
                how: String::new(),
            }),
            ..settings.clone()
        };
        let mut run = super::run::Run::new(self, prepared, &pilot_camera, &s, 1)?;
        let started = Instant::now();
        let measure = |run: &mut super::run::Run,
                       cam: &Camera,
                       s: &RenderSettings|
         -> Result<Option<Measured>> {
            run.set_camera(ctx, prepared, cam, s)?;
            let o = Blocking {
                whole: true,
                ..run.blocking(ctx, s)
            }
            .render_seed(PILOT_SEED, &mut |_, _| {})?;
            let r = &o.resolved;
            let pixels = crate::metrics::estimated_relmse_pixels(
                &r.film.beauty,
                &r.even,
                &r.odd,
                &r.counts,
                &r.split,
            );
            let samples: u64 = r.counts.iter().map(|&c| u64::from(c)).sum();
            let seen = pixels.iter().any(|t| *t > 0.0 && t.is_finite());
            Ok((seen && samples > 0 && !o.interrupted).then(|| Measured {
                pixels,
                rays: r.rays as f64 / samples as f64,
            }))
        };
        let over_time = || {
            settings
                .time
                .is_some_and(|t| started.elapsed().as_secs_f64() > PILOT_TIME_SHARE * t)
        };
        let mut tried = 1;
        let mut first = measure(&mut run, &pilot_camera, &s)?;
        if let Some(t) = settings.time {
            // The first candidate's rate sizes the pilot: each candidate its share of the time.
            let share = PILOT_TIME_SHARE * t / MAX_CANDIDATES as f64;
            let took = started.elapsed().as_secs_f64();
            // Too slow for the two candidates of the floor and one more move: none is tried.
            let least = PILOT_TIME_SHARE * t / LEAST_CANDIDATES;
            if took > least {
                if crate::vk::kernel_times() {
                    crate::note!(
                        "illum: allocation pilot: its first candidate took {took:.3} s, more than \
                         1/{LEAST_CANDIDATES} of its time ({least:.3} s): the integrator's counts"
                    );
                }
                run.keep(prepared);
                return Ok(Pilot {
                    counts: start,
                    tried,
                    stopped: true,
                    seconds: took,
                    size,
                });
            }
            let scale = (share / took).min(PILOT_PIXELS as f64 / PILOT_MIN_PIXELS as f64);
            if scale > 1.5 {
                let pixels = (f64::from(size.0 * size.1) * scale).min(PILOT_PIXELS as f64);
                (pilot_camera.width, pilot_camera.height) =
                    sized(pixels, camera.width, camera.height);
                run.keep(prepared);
                run = super::run::Run::new(self, prepared, &pilot_camera, &s, 1)?;
                first = measure(&mut run, &pilot_camera, &s)?;
                tried += 1;
            }
        }
        let size = (pilot_camera.width, pilot_camera.height);
        let Some(mut best_measured) = first else {
            // A black or unmeasurable pilot: nothing to choose by.
            run.keep(prepared);
            return Ok(Pilot {
                counts: start,
                tried,
                stopped: false,
                seconds: started.elapsed().as_secs_f64(),
                size,
            });
        };
        let mut best = start;
        let mut stopped = false;
        'steps: for step in 0..STEPS {
            // Whether the last move of this step went up: the next tries only that way (a line
            // search along the setting, one halving or doubling at a time).
            let mut up: Option<bool> = None;
            'search: loop {
                let from = best;
                for c in neighbours(step, best, scope) {
                    if up.is_some_and(|u| u != (key(step, &c) > key(step, &from))) {
                        continue;
                    }
                    if over_time() || tried >= MAX_CANDIDATES as u32 {
                        stopped = over_time();
                        break 'steps;
                    }
                    s.allocation = Some(Allocation {
                        counts: c,
                        how: String::new(),
                    });
                    tried += 1;
                    let m = measure(&mut run, &pilot_camera, &s)?;
                    if crate::vk::kernel_times()
                        && let Some(m) = &m
                    {
                        let (mine, theirs, se) = m.against(&best_measured);
                        crate::note!(
                            "illum: allocation pilot: {} costs {mine:.3e} against {theirs:.3e}, \
                         difference ± {se:.1e}",
                            c.describe(),
                        );
                    }
                    if let Some(m) = m
                        && if step == 0 {
                            m.beats(&best_measured, Z_SELECTION, SELECTION_MARGIN)
                        } else {
                            m.beats(&best_measured, Z, 1.0)
                        }
                    {
                        (best, best_measured) = (c, m);
                        if switch(step) {
                            break 'search;
                        }
                        up = Some(key(step, &c) > key(step, &from));
                        continue 'search;
                    }
                }
                break;
            }
        }
        if crate::vk::kernel_times() {
            crate::note!(
                "illum: allocation pilot: {tried} candidates in {:.3} s, chose {}",
                started.elapsed().as_secs_f64(),
                best.describe()
            );
        }
        run.keep(prepared);
        Ok(Pilot {
            counts: best,
            tried,
            stopped,
            seconds: started.elapsed().as_secs_f64(),
            size,
        })
    }
}

#[cfg(test)]
mod tests;
