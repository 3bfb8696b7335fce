//! The pilot's size, its candidates, its paired check and the counts' round trip, without a device.

use super::*;
use crate::layout::LIGHT_SELECT_SCAN;

fn settings(spp: u32, time: Option<f64>) -> RenderSettings {
    RenderSettings {
        spp,
        time,
        ..RenderSettings::default()
    }
}

#[test]
fn pilot_size_follows_the_render_not_the_job() {
    // 640x480 at 16 spp: 4.9M camera samples, 1/160 of them at 16 spp is 1920 pixels.
    let (w, h) = pilot_size(&settings(16, None), 640, 480).unwrap();
    assert!(
        u64::from(w * h) <= 1920 && u64::from(w * h) > 1800,
        "{w}x{h}"
    );
    assert!((f64::from(w) / f64::from(h) - 640.0 / 480.0).abs() < 0.05);
    // A crop or sample range leaves it as it is.
    let mut job = settings(16, None);
    job.samples = Some((4, 8));
    job.crop = Some(crate::film::Window {
        x0: 0,
        y0: 0,
        x1: 8,
        y1: 8,
    });
    assert_eq!(pilot_size(&job, 640, 480), Some((w, h)));
    // Large renders stop at PILOT_PIXELS, small ones have none.
    let (w, h) = pilot_size(&settings(1024, None), 1920, 1080).unwrap();
    assert!(u64::from(w * h) <= PILOT_PIXELS);
    assert_eq!(pilot_size(&settings(16, None), 64, 48), None);
    // A time budget: the smallest pilot, whatever the spp cap, sized again by its rate.
    let (w, h) = pilot_size(&settings(1, Some(1.0)), 640, 480).unwrap();
    assert!(u64::from(w * h) <= PILOT_MIN_PIXELS && u64::from(w * h) > 950);
}

#[test]
fn a_candidate_must_beat_the_best_by_more_than_its_noise() {
    let best = Measured {
        pixels: (0..1000).map(|i| 1.0 + f64::from(i % 7)).collect(),
        rays: 1.0,
    };
    // The same errors: no move.
    assert!(!best.beats(&best, Z, 1.0));
    // Half the error at the same rays, pixel for pixel: a move.
    let half = Measured {
        pixels: best.pixels.iter().map(|x| x / 2.0).collect(),
        rays: 1.0,
    };
    assert!(half.beats(&best, Z, 1.0));
    // 12% less at the same rays, in every pixel alike (the paired difference steady): a count
    // move, but not past the loop-or-tree margin.
    let steady = Measured {
        pixels: best.pixels.iter().map(|x| x * 0.88).collect(),
        rays: 1.0,
    };
    assert!(steady.beats(&best, Z, 1.0));
    assert!(!steady.beats(&best, Z_SELECTION, SELECTION_MARGIN));
    // Half the error at three times the rays (cost 0.5 x 4 against 1 x 2): no move.
    let costly = Measured {
        rays: 3.0,
        ..half.clone()
    };
    assert!(!costly.beats(&best, Z, 1.0));
    // 20% less on average, but from a few pixels' noise: the paired difference's standard
    // error is larger than the gain.
    let noisy = Measured {
        pixels: best
            .pixels
            .iter()
            .enumerate()
            .map(|(i, x)| if i % 100 == 0 { x * 50.0 } else { x * 0.25 })
            .collect(),
        rays: 1.0,
    };
    let (mine, theirs, se) = noisy.against(&best);
    assert!(
        mine < SELECTION_MARGIN * theirs && theirs - mine < Z * se,
        "{mine} {theirs} {se}"
    );
    assert!(!noisy.beats(&best, Z, 1.0));
    // One standard error (the loop against the tree) lets it through.
    assert!(noisy.beats(&best, Z_SELECTION, SELECTION_MARGIN));
    // Pixels left out (NaN) on either side are left out of both.
    let mut gaps = half.clone();
    gaps.pixels[3] = f64::NAN;
    assert!(gaps.beats(&best, Z, 1.0));
}

#[test]
fn candidates_move_one_setting_within_bounds() {
    let c = Counts {
        tree: false,
        light_samples: 4,
        brdf_samples: 2,
        dome_samples: 8,
        light_floor: 1,
        diffuse_mis: false,
    };
    let scope = |textured_dome, finite_lights, mis| Scope {
        textured_dome,
        finite_lights,
        selection: false,
        mis,
    };
    let plain = scope(false, true, true);
    // The loop or the tree only where both can run.
    assert!(neighbours(0, c, plain).is_empty());
    let both = Scope {
        selection: true,
        ..plain
    };
    assert_eq!(neighbours(0, c, both), vec![Counts { tree: true, ..c }]);
    let tree = Counts { tree: true, ..c };
    assert_eq!(neighbours(0, tree, both), vec![c]);
    assert_eq!(
        neighbours(1, c, plain),
        vec![Counts {
            light_floor: 4,
            ..c
        }]
    );
    // No finite light, or the tree (which loops over the infinite lights only): the floor
    // changes nothing.
    assert!(neighbours(1, c, scope(false, false, true)).is_empty());
    assert!(neighbours(1, tree, both).is_empty());
    let n = neighbours(
        2,
        Counts {
            light_floor: 4,
            ..c
        },
        plain,
    );
    assert_eq!(n.len(), 2);
    assert!(n.iter().all(|k| k.light_floor == k.light_samples));
    assert_eq!(neighbours(3, c, plain).len(), 2);
    assert!(neighbours(4, c, plain).is_empty());
    let dome = scope(true, true, true);
    let d = neighbours(4, c, dome);
    assert_eq!(
        d.iter().map(|k| k.dome_samples).collect::<Vec<_>>(),
        [4, 16]
    );
    let top = Counts {
        dome_samples: 16,
        brdf_samples: 1,
        ..c
    };
    assert_eq!(neighbours(4, top, dome).len(), 1);
    assert_eq!(neighbours(3, top, dome).len(), 1);
    // Diffuse MIS is toggled under MIS only.
    assert_eq!(
        neighbours(5, c, plain),
        vec![Counts {
            diffuse_mis: true,
            ..c
        }]
    );
    assert!(neighbours(5, c, scope(false, true, false)).is_empty());
    assert!(neighbours(STEPS, c, dome).is_empty());
}

#[test]
fn counts_round_trip_through_the_frame() {
    let mut f = Frame {
        light_tree: 0x1000,
        ..Frame::default()
    };
    let c = Counts {
        tree: true,
        light_samples: 8,
        brdf_samples: 1,
        dome_samples: 4,
        light_floor: 8,
        diffuse_mis: true,
    };
    c.apply(&mut f);
    assert_eq!(Counts::of(&f), c);
    let off = Counts {
        diffuse_mis: false,
        light_floor: 20,
        ..c
    };
    off.apply(&mut f);
    // The floor is clamped to N_max; diffuse MIS cleared.
    assert_eq!(
        Counts::of(&f),
        Counts {
            light_floor: 8,
            ..off
        }
    );
    assert_eq!(f.light_select, LIGHT_SELECT_TREE);
    Counts { tree: false, ..c }.apply(&mut f);
    assert_eq!(f.light_select, LIGHT_SELECT_LOOP);
    // Without a tree the lights are looped over whatever the counts say; a scan asked for
    // is kept.
    let mut bare = Frame::default();
    c.apply(&mut bare);
    assert_eq!(bare.light_select, LIGHT_SELECT_LOOP);
    assert!(!Counts::of(&bare).tree);
    bare.light_select = LIGHT_SELECT_SCAN;
    Counts { tree: false, ..c }.apply(&mut bare);
    assert_eq!(bare.light_select, LIGHT_SELECT_SCAN);
}
