//! Intel Open Image Denoise (OIDN 2), loaded at run time: its "RT" filter over the beauty with
//! the albedo and normal planes as guides, on OIDN's CPU device. The beauty itself is never
//! touched: `illum render --denoise` adds a `Denoised` layer beside it (so error reports and
//! merges stay exact), and `illum view` shows a denoised preview.
//!
//! The library is found at `$ILLUM_OIDN_LIBRARY`, else by the loader (`libOpenImageDenoise.so.2`
//! on its path), else in the `pyoidn` wheel that scripts/setup-debian.sh installs in the
//! repository's `.venv-py` (looked for above the executable and the working directory). A
//! missing library is an error naming what was tried.

use std::ffi::{CStr, CString, c_char, c_void};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

type Device = *mut c_void;
type Filter = *mut c_void;

/// OIDN_DEVICE_TYPE_CPU and OIDN_FORMAT_FLOAT3 (OpenImageDenoise/oidn.h).
const DEVICE_CPU: i32 = 1;
const FORMAT_FLOAT3: i32 = 3;

/// The C functions illum calls.
struct Api {
    new_device: unsafe extern "C" fn(i32) -> Device,
    commit_device: unsafe extern "C" fn(Device),
    device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> i32,
    device_int: unsafe extern "C" fn(Device, *const c_char) -> i32,
    release_device: unsafe extern "C" fn(Device),
    new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    #[allow(clippy::type_complexity)]
    set_image: unsafe extern "C" fn(
        Filter,
        *const c_char,
        *mut c_void,
        i32,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Filter),
    execute_filter: unsafe extern "C" fn(Filter),
    release_filter: unsafe extern "C" fn(Filter),
    /// Where the library was loaded from.
    path: String,
}

// SAFETY: plain function pointers into a library that stays loaded for the process.
unsafe impl Send for Api {}
unsafe impl Sync for Api {}

fn candidates() -> Vec<PathBuf> {
    let mut c = Vec::new();
    if let Some(p) = std::env::var_os("ILLUM_OIDN_LIBRARY").filter(|p| !p.is_empty()) {
        return vec![PathBuf::from(p)];
    }
    c.push(PathBuf::from("libOpenImageDenoise.so.2"));
    let mut roots: Vec<PathBuf> = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        roots.extend(exe.ancestors().skip(1).map(Path::to_path_buf));
    }
    if let Ok(cwd) = std::env::current_dir() {
        roots.extend(cwd.ancestors().map(Path::to_path_buf));
    }
    for root in roots {
        let lib = root.join(".venv-py").join("lib");
        let Ok(entries) = std::fs::read_dir(&lib) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e
                .path()
                .join("site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2");
            if p.exists() && !c.contains(&p) {
                c.push(p);
            }
        }
    }
    c
}

fn load() -> Result<Api, String> {
    let tried = candidates();
    for path in &tried {
        let Ok(name) = CString::new(path.as_os_str().as_encoded_bytes()) else {
            continue;
        };
        // SAFETY: dlopen of a shared library by name; it stays loaded for the process.
        let handle = unsafe { libc::dlopen(name.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        if handle.is_null() {
            continue;
        }
        let symbol = |s: &CStr| -> Result<*mut c_void, String> {
            // SAFETY: a symbol lookup in the library just opened.
            let f = unsafe { libc::dlsym(handle, s.as_ptr()) };
            if f.is_null() {
                Err(format!("{}: has no {s:?}", path.display()))
            } else {
                Ok(f)
            }
        };
        // SAFETY: the symbols are OIDN 2's C functions with these signatures (oidn.h).
        unsafe {
            return Ok(Api {
                new_device: function(symbol(c"oidnNewDevice")?),
                commit_device: function(symbol(c"oidnCommitDevice")?),
                device_error: function(symbol(c"oidnGetDeviceError")?),
                device_int: function(symbol(c"oidnGetDeviceInt")?),
                release_device: function(symbol(c"oidnReleaseDevice")?),
                new_filter: function(symbol(c"oidnNewFilter")?),
                set_image: function(symbol(c"oidnSetSharedFilterImage")?),
                set_bool: function(symbol(c"oidnSetFilterBool")?),
                commit_filter: function(symbol(c"oidnCommitFilter")?),
                execute_filter: function(symbol(c"oidnExecuteFilter")?),
                release_filter: function(symbol(c"oidnReleaseFilter")?),
                path: path.display().to_string(),
            });
        }
    }
    Err(format!(
        "the denoiser needs Intel Open Image Denoise 2 (libOpenImageDenoise.so.2), not found \
         (tried {}): scripts/setup-debian.sh installs it from PyPI's pyoidn wheel into .venv-py, \
         or set ILLUM_OIDN_LIBRARY to the library's path",
        tried
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

/// A symbol as the function pointer type `F`.
///
/// # Safety
/// The symbol must be a function of type `F`.
unsafe fn function<F: Copy>(symbol: *mut c_void) -> F {
    assert_eq!(std::mem::size_of::<F>(), std::mem::size_of::<*mut c_void>());
    // SAFETY: the caller's contract; same size, checked above.
    unsafe { std::mem::transmute_copy::<*mut c_void, F>(&symbol) }
}

fn api() -> Result<&'static Api, String> {
    static API: OnceLock<Result<Api, String>> = OnceLock::new();
    API.get_or_init(load).as_ref().map_err(Clone::clone)
}

/// An OIDN CPU device, kept for any number of images.
pub struct Denoiser {
    api: &'static Api,
    device: Device,
    /// OIDN's version, e.g. "2.5.1", and the library's path.
    pub version: String,
}

impl Denoiser {
    pub fn new() -> Result<Denoiser, String> {
        let api = api()?;
        // SAFETY: OIDN's documented calls on a device it returns.
        unsafe {
            let device = (api.new_device)(DEVICE_CPU);
            if device.is_null() {
                return Err(format!("{}: oidnNewDevice(CPU) failed", api.path));
            }
            // Owned from here: released on every path out.
            let mut d = Denoiser {
                api,
                device,
                version: String::new(),
            };
            (api.commit_device)(device);
            d.check("creating the CPU device")?;
            let v = (api.device_int)(device, c"version".as_ptr());
            d.version = format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100);
            Ok(d)
        }
    }

    /// What the header says of it.
    pub fn description(&self) -> String {
        format!(
            "Open Image Denoise {} (RT filter, HDR, albedo and normal guides, CPU)",
            self.version
        )
    }

    fn check(&self, what: &str) -> Result<(), String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: the device is live; the message, if any, is OIDN's own string.
        let code = unsafe { (self.api.device_error)(self.device, &mut message) };
        if code == 0 {
            return Ok(());
        }
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: a NUL-terminated string owned by OIDN until its next call.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Err(format!("Open Image Denoise, {what}: error {code}: {text}"))
    }

    /// The beauty `color` of a `width` x `height` image denoised with its `albedo` and `normal`
    /// planes (all row-major, the same size).
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[[f32; 3]],
        albedo: &[[f32; 3]],
        normal: &[[f32; 3]],
    ) -> Result<Vec<[f32; 3]>, String> {
        let n = width as usize * height as usize;
        if color.len() != n || albedo.len() != n || normal.len() != n {
            return Err(format!(
                "the planes to denoise have {}, {} and {} pixels, the image {width}x{height}",
                color.len(),
                albedo.len(),
                normal.len()
            ));
        }
        let mut output = vec![[0.0f32; 3]; n];
        let (w, h) = (width as usize, height as usize);
        // SAFETY: the filter reads the three planes and writes `output`, all n float3 pixels
        // that outlive its execution; it is released before returning.
        unsafe {
            let a = self.api;
            let filter = (a.new_filter)(self.device, c"RT".as_ptr());
            if filter.is_null() {
                self.check("creating the RT filter")?;
                return Err("Open Image Denoise: oidnNewFilter(RT) failed".into());
            }
            let image = |name: &CStr, data: *const [f32; 3]| {
                (a.set_image)(
                    filter,
                    name.as_ptr(),
                    data as *mut c_void,
                    FORMAT_FLOAT3,
                    w,
                    h,
                    0,
                    0,
                    0,
                )
            };
            image(c"color", color.as_ptr());
            image(c"albedo", albedo.as_ptr());
            image(c"normal", normal.as_ptr());
            image(c"output", output.as_mut_ptr());
            (a.set_bool)(filter, c"hdr".as_ptr(), true);
            (a.commit_filter)(filter);
            let committed = self.check("committing the filter");
            if committed.is_ok() {
                (a.execute_filter)(filter);
            }
            (a.release_filter)(filter);
            committed?;
            self.check("denoising")?;
        }
        Ok(output)
    }

    /// The film's beauty denoised: the emission seen directly (the Emission plane, free of
    /// lighting noise) is kept as rendered and the light reflected towards the camera (the
    /// beauty less it) denoised, so that a light seen directly keeps its radiance and its edge.
    pub fn denoise_film(&self, film: &crate::film::Film) -> Result<Vec<[f32; 3]>, String> {
        let reflected: Vec<[f32; 3]> = film
            .beauty
            .iter()
            .zip(&film.emission)
            .map(|(b, e)| std::array::from_fn(|c| b[c] - e[c]))
            .collect();
        let mut out = self.denoise(
            film.width,
            film.height,
            &reflected,
            &film.albedo,
            &film.normal,
        )?;
        for (o, e) in out.iter_mut().zip(&film.emission) {
            for c in 0..3 {
                o[c] += e[c];
            }
        }
        Ok(out)
    }

    /// `film` with a `Denoised` layer added ([`Denoiser::denoise_film`]; the beauty unchanged).
    pub fn add_layer(&self, film: &mut crate::film::Film) -> Result<(), String> {
        let rgb = self.denoise_film(film)?;
        film.aovs.push(crate::film::AovPlane {
            name: "Denoised".into(),
            rgb,
        });
        Ok(())
    }
}

impl Drop for Denoiser {
    fn drop(&mut self) {
        // SAFETY: the device is ours and no filter of it is alive.
        unsafe { (self.api.release_device)(self.device) };
    }
}
