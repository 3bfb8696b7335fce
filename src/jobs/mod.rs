//! Split renders: the jobs of one image (sample ranges and/or pixel windows, each written as a
//! partial EXR, src/jobs/partial.rs) and their exact merge. Merged jobs give the image a render
//! in one piece gives, bit for bit, because every film block is rendered whole by the jobs that
//! share it and block sums add exactly (src/film/mod.rs).

pub mod partial;

use crate::error::{Error, Result};
use crate::film::{self, Film, FilmSums, Window};
use crate::render::{RenderOutput, RenderSettings};
use crate::scene::Scene;
use partial::{PartData, PartInfo};
use std::path::{Path, PathBuf};

/// Every setting that changes a render's samples, as text: jobs of one image must agree on it.
pub fn settings_text(s: &RenderSettings) -> String {
    format!(
        "{} clamp={} nan_every={}{}",
        s.integrator.identity(),
        s.clamp.map_or("off".into(), |c| c.to_string()),
        s.inject_non_finite,
        s.adaptive.map_or(String::new(), |a| format!(
            " adaptive={:?} min_spp={}",
            a.target, a.min_spp
        ))
    )
}

/// FNV-1a, 64 bits: a stable hash (std's hashers may change between Rust releases).
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// A hash of everything in the validated scene that reaches the image (geometry, materials,
/// lights, textures, camera), as 16 hex digits; the scene's file name and description are left
/// out, so a copied scene file on another machine hashes the same.
pub fn scene_hash(scene: &Scene) -> String {
    let mut h = Fnv::new();
    h.write(format!("{:?}", scene.camera).as_bytes());
    h.write(format!("{:?}", scene.materials).as_bytes());
    h.write(format!("{:?}", scene.shapes).as_bytes());
    h.write(format!("{:?}", scene.lights).as_bytes());
    h.write(format!("{:?}", scene.instances).as_bytes());
    for m in &scene.meshes {
        h.write(format!("{} {:?}", m.name, m.material).as_bytes());
        h.write(bytemuck::cast_slice(&m.indices));
        for p in &m.positions {
            h.write(bytemuck::cast_slice(&p.to_array()));
        }
        for n in m.normals.iter().flatten() {
            h.write(bytemuck::cast_slice(&n.to_array()));
        }
        for t in m.tangents.iter().flatten() {
            h.write(bytemuck::cast_slice(&t.to_array()));
        }
        for uv in m.uvs.iter().flatten() {
            h.write(bytemuck::cast_slice(&uv.to_array()));
        }
    }
    for t in &scene.textures {
        h.write(
            format!(
                "{} {}x{} {:?} {:?}",
                t.name, t.width, t.height, t.filter, t.wrap
            )
            .as_bytes(),
        );
        for v in &t.texels {
            h.write(bytemuck::cast_slice(&v.to_array()));
        }
    }
    format!("{:016x}", h.0)
}

/// The description a render's job writes beside its sums. An interrupted render is no job: its
/// sums may hold part of a block it does not own, so it has no part to write.
pub fn part_info(
    scene: &Scene,
    settings: &RenderSettings,
    out: &RenderOutput,
    device: &str,
) -> Result<PartInfo> {
    if out.stats.interrupted {
        return Err(Error::Invalid(format!(
            "the job was interrupted after {} samples: an incomplete job has no part to write; render it again",
            out.stats.spp
        )));
    }
    let job = out.sums()?;
    Ok(PartInfo {
        samples: job.range,
        window: job.sums.window,
        frame: (scene.camera.width, scene.camera.height),
        spp: job.total_spp,
        seed: settings.seed,
        witness: out.stats.split.word(),
        scene_hash: scene_hash(scene),
        settings: settings_text(settings),
        trace: out.stats.trace.to_string(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        device: device.to_string(),
        render_seconds: out.stats.render_seconds,
        setup_seconds: out.stats.setup_seconds,
        aov_planes: job.sums.aov_planes.clone(),
    })
}

/// One job read back: where it came from, what it says, its sums.
pub struct Part {
    pub path: PathBuf,
    pub info: PartInfo,
    pub sums: FilmSums,
}

/// The image rebuilt from its jobs.
pub struct Merged {
    pub film: Film,
    pub spp: u32,
    pub seed: u64,
    pub trace: String,
    pub settings: String,
    /// Summed over the jobs.
    pub render_seconds: f64,
    pub setup_seconds: f64,
    pub devices: Vec<String>,
    pub non_finite_samples: u64,
    pub clamped_samples: u64,
    pub rays: u64,
    /// Which pixels split their samples (the parts' `illum.witness`).
    pub split: film::Split,
}

/// A part's file and header: all that the checks need.
pub struct PartHeader {
    pub path: PathBuf,
    pub info: PartInfo,
}

fn part_error(path: &Path, field: &str, message: String) -> Error {
    Error::Invalid(format!("{} ({field}): {message}", path.display()))
}

/// Checks that `parts` are the jobs of one image: same scene, seed, samples per pixel, settings,
/// AOV planes, trace path and version; windows inside the frame; and in every cell cut by the
/// windows' edges, sample ranges that tile 0..spp. Errors name the part and the field.
pub fn check(parts: &[PartHeader]) -> Result<()> {
    let first = parts
        .first()
        .ok_or_else(|| Error::Invalid("illum merge: no parts given".into()))?;
    let f = &first.info;
    for p in &parts[1..] {
        let i = &p.info;
        let checks: [(&str, String, String); 9] = [
            (
                "illum.sceneHash",
                i.scene_hash.clone(),
                f.scene_hash.clone(),
            ),
            ("illum.seed", i.seed.to_string(), f.seed.to_string()),
            (
                "illum.witness",
                i.witness.to_string(),
                f.witness.to_string(),
            ),
            ("illum.spp", i.spp.to_string(), f.spp.to_string()),
            (
                "illum.frame",
                format!("{:?}", i.frame),
                format!("{:?}", f.frame),
            ),
            ("illum.settings", i.settings.clone(), f.settings.clone()),
            (
                "illum.aovPlanes",
                format!("{:?}", i.aov_planes),
                format!("{:?}", f.aov_planes),
            ),
            ("illum.trace", i.trace.clone(), f.trace.clone()),
            ("illum.version", i.version.clone(), f.version.clone()),
        ];
        for (field, got, want) in checks {
            if got != want {
                return Err(part_error(
                    &p.path,
                    field,
                    format!(
                        "{got} where {} has {want}: not a job of the same image",
                        first.path.display()
                    ),
                ));
            }
        }
    }
    let (w, h) = f.frame;
    let spp = f.spp;
    for p in parts {
        let win = p.info.window;
        if win.x1 > w || win.y1 > h || win.x0 >= win.x1 || win.y0 >= win.y1 {
            return Err(part_error(
                &p.path,
                "illum.crop",
                format!("{win} is not a window of the {w}x{h} frame"),
            ));
        }
    }
    let cuts = |lo: fn(&Window) -> u32, hi: fn(&Window) -> u32, end: u32| {
        let mut v: Vec<u32> = parts
            .iter()
            .flat_map(|p| [lo(&p.info.window), hi(&p.info.window)])
            .chain([0, end])
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let xs = cuts(|w| w.x0, |w| w.x1, w);
    let ys = cuts(|w| w.y0, |w| w.y1, h);
    for y in ys.windows(2) {
        for x in xs.windows(2) {
            let cell = Window {
                x0: x[0],
                y0: y[0],
                x1: x[1],
                y1: y[1],
            };
            let mut here: Vec<&PartHeader> = parts
                .iter()
                .filter(|p| p.info.window.overlaps(&cell))
                .collect();
            here.sort_by_key(|p| p.info.samples);
            let mut next = 0;
            for (k, p) in here.iter().enumerate() {
                let (a, b) = p.info.samples;
                if a < next {
                    let q = here[k - 1];
                    return Err(part_error(
                        &p.path,
                        "illum.samples, illum.crop",
                        format!(
                            "samples {a}..{b} of pixels {cell} overlaps samples {}..{} of {} (a part given twice, or from another split?)",
                            q.info.samples.0,
                            q.info.samples.1,
                            q.path.display()
                        ),
                    ));
                }
                if a > next {
                    return Err(Error::Invalid(format!(
                        "illum merge: samples {next}..{a} of pixels {cell} are in no part (a part is missing)"
                    )));
                }
                next = b;
            }
            if next != spp {
                return Err(Error::Invalid(format!(
                    "illum merge: samples {next}..{spp} of pixels {cell} are in no part (a part is missing)"
                )));
            }
        }
    }
    Ok(())
}

/// FNV-1a of a block's float32 sums at one pixel: what a later copy of the block is checked
/// against, without keeping the first copy.
fn pixel_hash(v: &[f32]) -> u64 {
    let mut h = Fnv::new();
    h.write(bytemuck::cast_slice(v));
    h.0
}

/// Adds checked parts up one at a time, so that a merge holds one part in memory besides the
/// frame's sums.
struct Accumulator {
    width: u32,
    height: u32,
    aov_planes: Vec<String>,
    /// Frame pixels, row-major, `channels` values each.
    channels: usize,
    sums: Vec<i128>,
    /// Per boundary block (by its first sample) and frame pixel: the hash of the copy added and
    /// its part + 1 (0: none added yet). One flat table a block, made when a part first has it.
    seen: std::collections::HashMap<u32, Vec<(u64, u32)>>,
}

impl Accumulator {
    fn new(width: u32, height: u32, aov_planes: Vec<String>) -> Accumulator {
        let n = width as usize * height as usize;
        let channels = film::channels(aov_planes.len());
        Accumulator {
            width,
            height,
            aov_planes,
            channels,
            sums: crate::film::zeroed_sums(n * channels),
            seen: Default::default(),
        }
    }

    /// An accumulator for the frame and planes of the checked parts `headers`.
    fn for_parts(headers: &[PartHeader]) -> Accumulator {
        let f = &headers[0].info;
        Accumulator::new(f.frame.0, f.frame.1, f.aov_planes.clone())
    }

    /// Adds part `index` (of `headers`): its owned blocks, and each shared block it has that no
    /// earlier part added at that pixel (the jobs that share a block rendered it whole, so their
    /// copies must agree).
    fn add(&mut self, headers: &[PartHeader], index: usize, sums: &FilmSums) -> Result<()> {
        let win = headers[index].info.window;
        let c = self.channels;
        if sums.aov_planes != self.aov_planes || sums.window != win {
            return Err(part_error(
                &headers[index].path,
                "illum.aovPlanes, illum.crop",
                "its sums do not match its header".into(),
            ));
        }
        let w = self.width as usize;
        let row = win.width() as usize * c;
        let at = |y: u32| (y as usize * w + win.x0 as usize) * c;
        // A window row is a run of the frame's sums: add it as one slice.
        for (y, src) in (win.y0..win.y1).zip(sums.sums.chunks_exact(row)) {
            let dst = &mut self.sums[at(y)..at(y) + row];
            for (a, x) in dst.iter_mut().zip(src) {
                *a = a.saturating_add(*x);
            }
        }
        for b in &sums.boundary {
            for (i, v) in b.sums.chunks_exact(c).enumerate() {
                self.add_boundary(headers, index, (b.start, b.end), i, v)?;
            }
        }
        Ok(())
    }

    /// Adds part `index`'s data as read from its file, pixel by pixel from its channels (the
    /// part is never joined into pixels first: a merge holds the frame's sums and one part's
    /// decoded channels).
    fn add_data(&mut self, headers: &[PartHeader], index: usize, data: &PartData) -> Result<()> {
        let info = &headers[index].info;
        let win = info.window;
        let c = self.channels;
        if data.channels() != c || data.pixels != win.pixels() {
            return Err(part_error(
                &headers[index].path,
                "illum.aovPlanes, illum.crop",
                "its sums do not match its header".into(),
            ));
        }
        for i in 0..data.pixels {
            let px = self.frame_pixel(win, i);
            for (k, a) in self.sums[px * c..(px + 1) * c].iter_mut().enumerate() {
                *a = a.saturating_add(data.sum(i, k));
            }
        }
        let mut v = vec![0.0f32; c];
        for (start, end, channels) in &data.boundary {
            for i in 0..data.pixels {
                for (x, ch) in v.iter_mut().zip(channels) {
                    *x = ch[i];
                }
                self.add_boundary(headers, index, (*start, *end), i, &v)?;
            }
        }
        Ok(())
    }

    /// The frame pixel of pixel `i` (row-major) of window `win`.
    fn frame_pixel(&self, win: Window, i: usize) -> usize {
        let (x, y) = (
            win.x0 as usize + i % win.width() as usize,
            win.y0 as usize + i / win.width() as usize,
        );
        y * self.width as usize + x
    }

    /// Adds pixel `i`'s sums `v` of a boundary block of part `index` unless another part's copy
    /// was added, which it must then equal.
    fn add_boundary(
        &mut self,
        headers: &[PartHeader],
        index: usize,
        (start, end): (u32, u32),
        i: usize,
        v: &[f32],
    ) -> Result<()> {
        let c = self.channels;
        let px = self.frame_pixel(headers[index].info.window, i);
        let pixels = self.width as usize * self.height as usize;
        let seen = self
            .seen
            .entry(start)
            .or_insert_with(|| vec![(0, 0); pixels]);
        let hash = pixel_hash(v);
        match seen[px] {
            (_, 0) => {
                seen[px] = (hash, index as u32 + 1);
                film::add_block(&mut self.sums[px * c..(px + 1) * c], v, c);
            }
            (h, q) if h != hash => {
                return Err(part_error(
                    &headers[index].path,
                    "block",
                    format!(
                        "its samples {start}..{end} differ from those of {}",
                        headers[q as usize - 1].path.display()
                    ),
                ));
            }
            _ => {}
        }
        Ok(())
    }

    fn finish(self, headers: &[PartHeader]) -> Merged {
        let f = &headers[0].info;
        let split = film::Split::from_word(f.witness);
        let r = film::resolve(
            &self.sums,
            &self.aov_planes,
            (self.width, self.height),
            f.spp,
            split,
            (0, 0),
        );
        let mut devices: Vec<String> = headers.iter().map(|p| p.info.device.clone()).collect();
        devices.sort();
        devices.dedup();
        Merged {
            film: r.film,
            spp: f.spp,
            seed: f.seed,
            trace: f.trace.clone(),
            settings: f.settings.clone(),
            render_seconds: headers.iter().map(|p| p.info.render_seconds).sum(),
            setup_seconds: headers.iter().map(|p| p.info.setup_seconds).sum(),
            devices,
            non_finite_samples: r.non_finite_samples,
            clamped_samples: r.clamped_samples,
            rays: r.rays,
            split,
        }
    }
}

/// Checks that `parts` are the jobs of one image ([`check`]) and adds them up exactly.
pub fn merge(parts: &[Part]) -> Result<Merged> {
    let headers: Vec<PartHeader> = parts
        .iter()
        .map(|p| PartHeader {
            path: p.path.clone(),
            info: p.info.clone(),
        })
        .collect();
    check(&headers)?;
    let mut acc = Accumulator::for_parts(&headers);
    for (k, p) in parts.iter().enumerate() {
        acc.add(&headers, k, &p.sums)?;
    }
    Ok(acc.finish(&headers))
}

/// [`merge`] of partial EXR files, reading their headers first (so a mismatch fails before any
/// data is read) and then one part at a time.
pub fn merge_files(paths: &[PathBuf]) -> Result<Merged> {
    let mut headers = Vec::with_capacity(paths.len());
    for path in paths {
        headers.push(PartHeader {
            path: path.clone(),
            info: crate::jobs::partial::read_partial_info(path)?,
        });
    }
    check(&headers)?;
    let mut acc = Accumulator::for_parts(&headers);
    for (k, path) in paths.iter().enumerate() {
        let (info, data) = crate::jobs::partial::read_partial_data(path)?;
        if info != headers[k].info {
            return Err(part_error(path, "header", "changed while merging".into()));
        }
        acc.add_data(&headers, k, &data)?;
    }
    Ok(acc.finish(&headers))
}
