//! AOV planes that an integrator declares (`Integrator::aov_planes`): the film carries them as
//! exactly as its own planes. Sums of a film with two extra planes, split into two sample ranges
//! written as partial EXRs, read back and merged, equal the sums in one piece bit for bit, and
//! the final EXR holds them as `<Name>.R/G/B` means; parts with other planes are refused, naming
//! the part and the field. The device side (the "aovs" buffer read back and cleared with the
//! film) is checked on buffers filled from the host, so no kernel needs to write planes.

mod common;
use common::*;
use illum::film::{self, AOV_CHANNELS, BoundaryBlock, FILM_CHANNELS, FilmSums, Window};
use illum::jobs::partial::{PartInfo, read_partial, read_partial_info, write_partial};
use illum::jobs::{Part, merge, merge_files};
use illum::output::{AovPlane, Film, ImageMetadata, read_exr, write_exr};
use std::path::PathBuf;

/// 7x5 pixels, 600 samples: blocks 0..256, 256..512, 512..600.
const W: u32 = 7;
const H: u32 = 5;
const SPP: u32 = 600;
const BLOCKS: [(u32, u32); 3] = [(0, 256), (256, 512), (512, 600)];

fn planes(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// The float32 sums a device would leave for block `start` of a film with `channels` channels a
/// pixel: arbitrary but fixed values of all magnitudes (so float64 rounding would show), counts
/// where FilmPixel has counts, and the block's `samples` where it counts them.
fn block_sums(start: u32, samples: u32, channels: usize) -> Vec<f32> {
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15 ^ u64::from(start));
    let pixels = (W * H) as usize;
    (0..pixels * channels)
        .map(|i| {
            let u = rng.uniform_f32();
            match i % channels {
                // clamped, rays, hits, non_finite: counts; samples: the block's.
                3 | 7 | 11 | 19 => (u * 256.0).floor(),
                23 => samples as f32,
                c if c >= FILM_CHANNELS && (c - FILM_CHANNELS) % AOV_CHANNELS == 3 => 0.0,
                c => u * 10f32.powi((c % 7) as i32 - 3) * 256.0,
            }
        })
        .collect()
}

/// The sums of samples `range` of the whole frame, as a render job keeps them: whole blocks in
/// fixed point, partly owned ones kept as boundary blocks.
fn job_sums(range: (u32, u32), aov_planes: &[String]) -> FilmSums {
    let mut sums = FilmSums::new(Window::full(W, H), aov_planes.to_vec());
    let c = sums.channels();
    for (start, end) in BLOCKS {
        if end <= range.0 || start >= range.1 {
            continue;
        }
        let block = block_sums(start, end - start, c);
        if start >= range.0 && end <= range.1 {
            sums.add_block(&block);
        } else {
            sums.boundary.push(BoundaryBlock {
                start,
                end,
                sums: block,
            });
        }
    }
    sums
}

fn info(range: (u32, u32), aov_planes: &[String]) -> PartInfo {
    PartInfo {
        samples: range,
        window: Window::full(W, H),
        frame: (W, H),
        spp: SPP,
        seed: 3,
        witness: film::Split::ALL.word(),
        scene_hash: "0123456789abcdef".into(),
        settings: "integrator=test".into(),
        trace: "bvh".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        device: "none".into(),
        render_seconds: 1.0,
        setup_seconds: 0.5,
        aov_planes: aov_planes.to_vec(),
    }
}

/// Writes samples `range` as the partial EXR `name` and reads it back.
fn part(name: &str, range: (u32, u32), aov_planes: &[String]) -> Part {
    let path = temp_path(&format!("{name}.exr"));
    let sums = job_sums(range, aov_planes);
    write_partial(&path, &info(range, aov_planes), &sums).unwrap();
    let (info, read) = read_partial(&path).unwrap();
    assert_eq!(read, sums, "{name}: the partial EXR reads back exactly");
    assert_eq!(info.aov_planes, aov_planes);
    Part {
        path,
        info,
        sums: read,
    }
}

#[test]
fn aov_planes_split_and_merged_are_bit_identical_and_reach_the_exr() {
    let names = planes(&["Direct", "IndirectDiffuse"]);
    let one = job_sums((0, SPP), &names);
    assert_eq!(one.channels(), FILM_CHANNELS + 2 * AOV_CHANNELS);
    assert!(one.boundary.is_empty());
    let whole = film::resolve(&one.sums, &names, (W, H), SPP, film::Split::ALL, (0, 0)).film;
    // Two jobs split inside block 256..512, which both keep whole.
    let parts = vec![
        part("aov-a", (0, 300), &names),
        part("aov-b", (300, SPP), &names),
    ];
    assert_eq!(parts[0].sums.boundary.len(), 1);
    let merged = merge(&parts).unwrap();
    assert_eq!(
        merged.film, whole,
        "merged parts differ from the film in one piece"
    );
    let paths: Vec<PathBuf> = parts.iter().map(|p| p.path.clone()).collect();
    let streamed = merge_files(&paths).unwrap();
    assert_eq!(streamed.film, whole);

    // The planes are the means of their sums, in the order declared.
    let film = &merged.film;
    assert_eq!(film.aovs.len(), 2);
    assert_eq!(film.aovs[0].name, "Direct");
    assert_eq!(film.aovs[1].name, "IndirectDiffuse");
    let c = one.channels();
    for (k, plane) in film.aovs.iter().enumerate() {
        for (i, rgb) in plane.rgb.iter().enumerate() {
            for (ch, &v) in rgb.iter().enumerate() {
                let at = FILM_CHANNELS + AOV_CHANNELS * k + ch;
                let mean = film::from_fixed(one.sums[i * c + at], at) / f64::from(SPP);
                assert_eq!(v, mean as f32, "{} pixel {i}", plane.name);
            }
        }
    }
    assert!(film.aovs[0].rgb.iter().any(|p| p[0] != 0.0));

    // The final EXR has Direct.R/G/B and IndirectDiffuse.R/G/B as float32 means.
    let path = temp_path("aov-merged.exr");
    write_exr(&path, film, &ImageMetadata::default()).unwrap();
    let exr = read_exr(&path).unwrap();
    for plane in &film.aovs {
        for (ch, comp) in ["R", "G", "B"].iter().enumerate() {
            let name = format!("{}.{comp}", plane.name);
            let data = exr
                .channel(&name)
                .unwrap_or_else(|| panic!("the EXR has no {name}"));
            let want: Vec<f32> = plane.rgb.iter().map(|p| p[ch]).collect();
            assert_eq!(data, &want[..], "{name}");
        }
    }
    assert!(exr.channel("R").is_some() && exr.channel("Albedo.R").is_some());
}

#[test]
fn merge_refuses_parts_with_other_aov_planes() {
    let a = part("aov-p1", (0, 300), &planes(&["Direct", "IndirectDiffuse"]));
    let b = part("aov-p2", (300, SPP), &planes(&["Direct", "Reflection"]));
    let none = part("aov-p3", (300, SPP), &[]);
    for other in [b, none] {
        let name = other.path.display().to_string();
        let paths = vec![a.path.clone(), other.path.clone()];
        for e in [merge(&[a_copy(&a), other]).err(), merge_files(&paths).err()] {
            let msg = e.expect("merged parts with other AOV planes").to_string();
            assert!(
                msg.contains(&name) && msg.contains("illum.aovPlanes"),
                "{msg:?} names neither the part nor the field"
            );
        }
    }
    // Without planes, a partial EXR's header names none.
    assert!(
        read_partial_info(&temp_path("aov-p3.exr"))
            .unwrap()
            .aov_planes
            .is_empty()
    );
}

fn a_copy(p: &Part) -> Part {
    Part {
        path: p.path.clone(),
        info: p.info.clone(),
        sums: p.sums.clone(),
    }
}

#[test]
fn films_with_bad_aov_names_are_not_written() {
    for bad in ["direct", "Albedo", "Variance", "Dir.ect", ""] {
        let mut film = Film::new(2, 2);
        film.aovs.push(AovPlane {
            name: bad.into(),
            rgb: vec![[0.0; 3]; 4],
        });
        let path = temp_path("aov-bad.exr");
        let e = write_exr(&path, &film, &ImageMetadata::default()).unwrap_err();
        assert!(e.to_string().contains("aov-bad.exr"), "{e}");
    }
    let mut film = Film::new(2, 2);
    for _ in 0..2 {
        film.aovs.push(AovPlane {
            name: "Direct".into(),
            rgb: vec![[0.0; 3]; 4],
        });
    }
    let e = write_exr(
        &temp_path("aov-twice.exr"),
        &film,
        &ImageMetadata::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("twice"), "{e}");
    film.aovs.pop();
    film.aovs[0].rgb.pop();
    let e = write_exr(
        &temp_path("aov-short.exr"),
        &film,
        &ImageMetadata::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("Direct"), "{e}");
}

/// The device side: download_window interleaves each pixel's FilmPixel with its AOV vec4s
/// ([pixel][plane] on the device) for a window inside the device film's own window (which need
/// not start at the image's corner), and clear zeroes both buffers.
#[test]
fn device_aov_planes_are_read_back_and_cleared_with_the_film() {
    use ash::vk::BufferUsageFlags as U;
    let ctx = context();
    let (w, h, p) = (5u32, 4u32, 3usize);
    let pixels = (w * h) as usize;
    // The film covers pixels (2, 7) to (6, 10) of a larger image.
    let covered = Window {
        x0: 2,
        y0: 7,
        x1: 2 + w,
        y1: 7 + h,
    };
    let film_data: Vec<f32> = (0..pixels * FILM_CHANNELS).map(|i| i as f32).collect();
    let aov_data: Vec<f32> = (0..pixels * p * AOV_CHANNELS)
        .map(|i| -(i as f32) - 0.5)
        .collect();
    let usage = U::STORAGE_BUFFER | U::TRANSFER_SRC | U::TRANSFER_DST;
    let film_buf = ctx.upload("film", &film_data, usage).unwrap();
    let aov_buf = ctx.upload("aovs", &aov_data, usage).unwrap();
    // Reads through a kept host buffer, as a render's are: a later read sees the new data.
    let kept = std::sync::Mutex::new(None);
    let device = film::DeviceFilm {
        film: &film_buf,
        aovs: Some(&aov_buf),
        aov_planes: p,
        window: covered,
        readback: Some(&kept),
    };
    let window = Window {
        x0: 3,
        y0: 8,
        x1: 6,
        y1: 10,
    };
    let got = film::download_window(&ctx, device, window).unwrap();
    let c = film::channels(p);
    assert_eq!(got.len(), window.pixels() * c);
    let mut i = 0;
    for y in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            let px = ((y - covered.y0) * w + x - covered.x0) as usize;
            let want: Vec<f32> = film_data[px * FILM_CHANNELS..(px + 1) * FILM_CHANNELS]
                .iter()
                .chain(&aov_data[px * p * AOV_CHANNELS..(px + 1) * p * AOV_CHANNELS])
                .copied()
                .collect();
            assert_eq!(&got[i * c..(i + 1) * c], &want[..], "pixel {x},{y}");
            i += 1;
        }
    }
    // A block's commit adds exactly what download_window reads (to sums that hold something
    // already), then clears the device film.
    let whole = film::download_window(&ctx, device, covered).unwrap();
    let mut sums = film::FilmSums::new(covered, vec!["A".into(), "B".into(), "C".into()]);
    let mut expected = film::FilmSums::new(covered, sums.aov_planes.clone());
    sums.add_block(&whole);
    expected.add_block(&whole);
    expected.add_block(&whole);
    film::commit_block(&ctx, device, &mut sums).unwrap();
    assert_eq!(sums.sums, expected.sums);
    let cleared = film::download_window(&ctx, device, covered).unwrap();
    assert!(cleared.iter().all(|&x| x == 0.0));
    film::clear(&ctx, device).unwrap();
    assert_no_validation_messages(&ctx);
}
