//! The library's layers point only down: every `crate::` path in a module names a module of a
//! lower layer (or its own). A new upward import fails here with the file and line; moving a
//! module between layers is a change to [`LAYERS`] and docs/architecture.md together.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The top-level modules of `src/`, lowest layer first.
const LAYERS: &[&[&str]] = &[
    // The layout shared by Rust and GLSL, compiled kernels, error metrics (pure math), and
    // `note!` (messages to stderr that cannot fail a render).
    &["layout", "shaders", "metrics", "note"],
    // The Vulkan layer: knows nothing of rendering.
    &["vk"],
    // The scene description: files in, validated host types out.
    &["scene"],
    // The library's error: wraps the two above (output errors come in through `From`).
    &["error"],
    // The scene on the device, then its trace structure.
    &["gpu_scene"],
    &["trace"],
    // Film sums, blocks and the resolved film: below both render and output; the denoiser, on
    // resolved films.
    &["film"],
    &["denoise"],
    // The render core: driver, prepared scenes, sessions, the integrator seam.
    &["render"],
    // The integrators and their table.
    &["integrators"],
    // Image files, then what is built on renders and files: split renders, reports.
    &["output"],
    &["jobs", "report"],
    // Comparisons of integrators, techniques and allocations at equal time: on reports.
    &["compare"],
    // Tools and front ends (the window over the render core, outputs and the denoiser).
    &["stress"],
    &["view"],
    &["cli", "capi"],
];

/// Items the crate's root re-exports, by the module that defines them.
const ROOT_ITEMS: &[(&str, &str)] = &[("Error", "error"), ("Result", "error")];

fn layer_of(module: &str) -> Option<usize> {
    let module = ROOT_ITEMS
        .iter()
        .find(|(item, _)| *item == module)
        .map_or(module, |(_, m)| m);
    LAYERS.iter().position(|l| l.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The line's code: without a `//` comment (string contents do not hold `crate::` paths here).
fn code(line: &str) -> &str {
    line.find("//").map_or(line, |i| &line[..i])
}

fn ident_at(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// The top-level modules that `text` names through `crate::`, with their lines.
fn imports(text: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().map(code).collect();
    let joined = lines.join("\n");
    let line_of = |offset: usize| joined[..offset].matches('\n').count() + 1;
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = joined[from..].find("crate::") {
        let start = from + i;
        let at = start + "crate::".len();
        from = at;
        // Not a path of another crate (`my_crate::`) or a `$crate::` in a macro.
        let before = joined[..start].chars().last();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '$') {
            continue;
        }
        let rest = &joined[at..];
        if let Some(group) = rest.strip_prefix('{') {
            // `crate::{a::b, c}`: the first segment of each item at depth 0.
            let (mut depth, mut start) = (0, true);
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => start = true,
                    c if start && (c.is_ascii_alphabetic() || c == '_') => {
                        out.push((ident_at(&group[k..]).to_string(), line_of(at)));
                        start = false;
                    }
                    _ => {}
                }
            }
        } else {
            let id = ident_at(rest);
            if !id.is_empty() {
                out.push((id.to_string(), line_of(at)));
            }
        }
    }
    out
}

#[test]
fn imports_point_down_the_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut counts: BTreeMap<(String, String), usize> = BTreeMap::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        if module == "lib" || module == "main" {
            continue;
        }
        let own = layer_of(&module)
            .unwrap_or_else(|| panic!("src/{module}: not in tests/layers.rs LAYERS"));
        let text = std::fs::read_to_string(f).unwrap();
        for (target, line) in imports(&text) {
            if target == module || target == "self" || target == "super" {
                continue;
            }
            let to = layer_of(&target).unwrap_or_else(|| {
                panic!(
                    "src/{}:{line}: crate::{target} is not in LAYERS",
                    rel.display()
                )
            });
            *counts.entry((module.clone(), target.clone())).or_default() += 1;
            if to >= own {
                violations.push(format!(
                    "src/{}:{line}: {module} (layer {own}) uses crate::{target} (layer {to})",
                    rel.display()
                ));
            }
        }
    }
    assert!(
        violations.is_empty(),
        "imports that point up or sideways:\n{}",
        violations.join("\n")
    );
    // The check sees the imports it should (it would pass vacuously if the parser broke).
    assert!(counts.contains_key(&("render".into(), "trace".into())));
    assert!(counts.contains_key(&("cli".into(), "render".into())));
    assert!(counts.contains_key(&("integrators".into(), "render".into())));
}

#[test]
fn the_parser_reads_paths_and_groups() {
    let text = "use crate::{film::{self, Window}, vk};\nlet x = crate::scene::load(p); // crate::cli\n/// [`crate::output`]\nuse $crate::x; my_crate::y";
    let got: Vec<(String, usize)> = imports(text);
    let names: Vec<&str> = got.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["film", "vk", "scene"]);
    assert_eq!(got[2].1, 2);
}
