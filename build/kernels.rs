//! Compiling GLSL kernels to SPIR-V with shaderc, shared by the crate's build script (the
//! library's kernels, glsl/) and the test kernels' (tests/kernels/), so that both compile alike.
//!
//! A kernel's Rust name is its file stem, so stems are unique. Each kernel is compiled once per
//! trace backend (`rq`: hardware ray queries, `bvh`: illum's compute BVH) when its first line says
//! `// illum-variants: rq bvh` (default: one plain variant). Feature switches within a variant are
//! specialization constants, folded at pipeline creation.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

pub const VARIANT_DEFINES: &[(&str, &[&str])] = &[
    ("rq", &["TRACE_RAYQUERY"]),
    ("bvh", &["TRACE_BVH"]),
    ("plain", &[]),
];

/// Every `*.comp` and `*.glsl` below `dir`.
pub fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let p = e.unwrap().path();
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|e| e == "comp" || e == "glsl") {
            out.push(p);
        }
    }
}

/// Compiles every kernel (`*.comp`) of `sources` in each of its variants into `out` and returns
/// the Rust index of their SPIR-V (`pub const <STEM>_<VARIANT>: &[u8]`), headed by `header`.
/// Includes are paths from `glsl`. Panics (failing the build) with every compiler message.
pub fn compile_kernels(glsl: &Path, sources: &[PathBuf], out: &Path, header: &str) -> String {
    let compiler = shaderc::Compiler::new().expect("shaderc: cannot create a compiler");
    let mut index = format!(
        "{header}\n/// Whether the kernels time their regions (ILLUM_PROFILE_KERNELS=1 at build time).\n\
         pub const PROFILED: bool = {};\n",
        profiled()
    );
    let mut failures = Vec::new();
    let mut kernels: Vec<&PathBuf> = sources
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "comp"))
        .collect();
    kernels.sort();
    for kernel in kernels {
        let text = fs::read_to_string(kernel).unwrap();
        let stem = kernel.file_stem().unwrap().to_string_lossy().to_string();
        let variants: Vec<&str> = text
            .lines()
            .next()
            .and_then(|l| l.trim().strip_prefix("// illum-variants:"))
            .map(|v| v.split_whitespace().collect())
            .unwrap_or_else(|| vec!["plain"]);
        for variant in variants {
            let defines = VARIANT_DEFINES
                .iter()
                .find(|(n, _)| *n == variant)
                .unwrap_or_else(|| panic!("{}: unknown variant {variant}", kernel.display()))
                .1;
            let mut defines = defines.to_vec();
            // The kernels that time their regions also compile that way in every build, so
            // the measurement build cannot rot unseen.
            if profiled() {
                defines.push("ILLUM_PROFILE");
            } else if text.contains("PROF_START()") {
                let mut timed = defines.clone();
                timed.push("ILLUM_PROFILE");
                if let Err(msg) = compile(&compiler, glsl, kernel, &text, &timed) {
                    failures.push(format!("with ILLUM_PROFILE: {msg}"));
                }
            }
            match compile(&compiler, glsl, kernel, &text, &defines) {
                Ok(words) => {
                    let name = format!("{stem}.{variant}.spv");
                    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
                    fs::write(out.join(&name), bytes).unwrap();
                    let ident = format!("{}_{}", stem.to_uppercase(), variant.to_uppercase());
                    writeln!(
                        index,
                        "pub const {ident}: &[u8] = include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{name}\"));"
                    )
                    .unwrap();
                }
                Err(msg) => failures.push(msg),
            }
        }
    }
    if !failures.is_empty() {
        for f in &failures {
            eprintln!("{f}");
        }
        panic!("GLSL compilation failed:\n{}", failures.join("\n"));
    }
    index
}

/// Whether the kernels time their regions (glsl/shared/profile.glsl): `ILLUM_PROFILE_KERNELS=1
/// cargo build`, for measurement only.
pub fn profiled() -> bool {
    std::env::var("ILLUM_PROFILE_KERNELS").is_ok_and(|v| v == "1")
}

pub fn compile(
    compiler: &shaderc::Compiler,
    glsl: &Path,
    path: &Path,
    text: &str,
    defines: &[&str],
) -> Result<Vec<u32>, String> {
    let mut opts = shaderc::CompileOptions::new().unwrap();
    opts.set_target_env(
        shaderc::TargetEnv::Vulkan,
        shaderc::EnvVersion::Vulkan1_2 as u32,
    );
    opts.set_target_spirv(shaderc::SpirvVersion::V1_5);
    opts.set_source_language(shaderc::SourceLanguage::GLSL);
    // No spirv-opt: its inlining hands the driver one function holding a copy of every callee per
    // call site (the full kernel: 2.7 MB) before specialization constants can drop the unused
    // ones, and lavapipe's SPIR-V-to-NIR step took 3.5 times as long on it; the driver inlines
    // and optimizes itself, and the kernels run as fast (docs/performance-kernels.md, "Kernel
    // compilation").
    opts.set_optimization_level(shaderc::OptimizationLevel::Zero);
    opts.set_generate_debug_info();
    opts.set_warnings_as_errors();
    for d in defines {
        opts.add_macro_definition(d, Some("1"));
    }
    // Every include names a path from glsl/ (`#include "lights/light_tree.glsl"`), whoever
    // includes it: one name per file, the same in every folder.
    let glsl_root = glsl.to_path_buf();
    opts.set_include_callback(move |name, _ty, from, _depth| {
        let path = glsl_root.join(name);
        match fs::read_to_string(&path) {
            Ok(content) => Ok(shaderc::ResolvedInclude {
                resolved_name: path.to_string_lossy().into_owned(),
                content,
            }),
            Err(e) => Err(format!(
                "{from}: include \"{name}\" (a path from glsl/): {e}"
            )),
        }
    });
    let file = path.to_string_lossy();
    compiler
        .compile_into_spirv(
            text,
            shaderc::ShaderKind::Compute,
            &file,
            "main",
            Some(&opts),
        )
        .map(|a| a.as_binary().to_vec())
        .map_err(|e| format!("{e}"))
}

/// Compiles every piece (the `*.glsl` among `sources`) as a kernel of its own, then all of them in
/// one kernel in sorted order and again in reverse order, in each trace variant: so each piece
/// includes what it uses, and none depends on what was included before it. Panics (failing the
/// build) with every compiler message.
pub fn check_pieces(glsl: &Path, sources: &[PathBuf]) {
    let compiler = shaderc::Compiler::new().expect("shaderc: cannot create a compiler");
    let mut pieces: Vec<String> = sources
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "glsl"))
        .map(|p| {
            let rel = p.strip_prefix(glsl).unwrap_or(p);
            rel.components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect::<Vec<_>>()
                .join("/")
        })
        .collect();
    pieces.sort();
    let kernel = |includes: &mut dyn Iterator<Item = &String>| {
        let mut text = String::from("#version 460\n");
        for name in includes {
            writeln!(text, "#include \"{name}\"").unwrap();
        }
        text.push_str("layout(local_size_x = 1) in;\nvoid main() {}\n");
        text
    };
    let mut cases: Vec<(String, String)> = pieces
        .iter()
        .map(|name| (name.clone(), kernel(&mut std::iter::once(name))))
        .collect();
    let every = kernel(&mut pieces.iter());
    cases.push(("every piece".into(), every.clone()));
    cases.push((
        "every piece, reversed".into(),
        kernel(&mut pieces.iter().rev()),
    ));
    let mut failures = Vec::new();
    for (variant, defines) in VARIANT_DEFINES.iter().filter(|(n, _)| *n != "plain") {
        for (what, text) in &cases {
            let name = glsl.join(format!("{what} alone ({variant})"));
            if let Err(e) = compile(&compiler, glsl, &name, text, defines) {
                failures.push(e);
            }
        }
        // The pieces as a measurement build compiles them (glsl/shared/profile.glsl).
        let mut timed = defines.to_vec();
        timed.push("ILLUM_PROFILE");
        let name = glsl.join(format!("every piece with ILLUM_PROFILE ({variant})"));
        if let Err(e) = compile(&compiler, glsl, &name, &every, &timed) {
            failures.push(e);
        }
    }
    assert!(
        failures.is_empty(),
        "GLSL pieces that do not compile on their own:\n{}",
        failures.join("\n")
    );
}
