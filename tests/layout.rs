//! The layout contract: every struct of glsl/shared/layout.glsl has the same size, member names
//! and member offsets in the SPIR-V glslang produced (glsl/tests/layout_check.comp, scalar
//! layout) as its Rust mirror in src/layout.rs.

use std::collections::HashMap;

const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_ARRAY_STRIDE: u32 = 6;
const DECORATION_OFFSET: u32 = 35;

fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

#[derive(Default)]
struct Reflection {
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    offsets: HashMap<(u32, u32), u32>,
    strides: HashMap<u32, u32>,
    runtime_arrays: HashMap<u32, u32>, // array id -> element type
    structs: HashMap<u32, usize>,      // struct id -> member count
}

fn reflect(spirv: &[u8]) -> Reflection {
    let words: Vec<u32> = spirv
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(words[0], 0x0723_0203, "not SPIR-V");
    let mut r = Reflection::default();
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        let op = words[i] & 0xffff;
        let ins = &words[i..i + count];
        match op {
            OP_NAME => {
                r.names.insert(ins[1], string(&ins[2..]));
            }
            OP_MEMBER_NAME => {
                r.member_names.insert((ins[1], ins[2]), string(&ins[3..]));
            }
            OP_MEMBER_DECORATE if ins[3] == DECORATION_OFFSET => {
                r.offsets.insert((ins[1], ins[2]), ins[4]);
            }
            OP_DECORATE if ins[2] == DECORATION_ARRAY_STRIDE => {
                r.strides.insert(ins[1], ins[3]);
            }
            OP_TYPE_RUNTIME_ARRAY => {
                r.runtime_arrays.insert(ins[1], ins[2]);
            }
            OP_TYPE_STRUCT => {
                r.structs.insert(ins[1], count - 2);
            }
            _ => {}
        }
        i += count.max(1);
    }
    r
}

#[test]
fn rust_mirrors_match_the_glsl_layout() {
    let r = reflect(illum::shaders::LAYOUT_CHECK_PLAIN);
    let mut problems = Vec::new();
    let expected = illum::layout::reflection();
    for (name, size, fields) in &expected {
        // glslang may emit several ids for one struct name (one per use); all must agree.
        let ids: Vec<u32> = r
            .structs
            .keys()
            .copied()
            .filter(|id| r.names.get(id).map(String::as_str) == Some(*name))
            .collect();
        if ids.is_empty() {
            problems.push(format!("{name}: not found in layout_check.comp's SPIR-V"));
            continue;
        }
        for id in ids {
            if r.structs[&id] != fields.len() {
                problems.push(format!(
                    "{name}: GLSL has {} members, Rust {}",
                    r.structs[&id],
                    fields.len()
                ));
            }
            for (m, (field, offset)) in fields.iter().enumerate() {
                let m = m as u32;
                let gname = r.member_names.get(&(id, m)).cloned().unwrap_or_default();
                if gname != *field {
                    problems.push(format!(
                        "{name}: member {m} is `{gname}` in GLSL, `{field}` in Rust"
                    ));
                }
                match r.offsets.get(&(id, m)) {
                    Some(&o) if o as usize == *offset => {}
                    Some(&o) => problems.push(format!(
                        "{name}.{field}: offset {o} in GLSL, {offset} in Rust"
                    )),
                    None => problems.push(format!("{name}.{field}: no offset in SPIR-V")),
                }
            }
            // The struct's size is the stride of a runtime array of it.
            let stride = r
                .runtime_arrays
                .iter()
                .find(|(_, elem)| **elem == id)
                .and_then(|(arr, _)| r.strides.get(arr));
            if let Some(&s) = stride
                && s as usize != *size
            {
                problems.push(format!("{name}: size {s} in GLSL, {size} in Rust"));
            }
        }
    }
    // Every struct used as an array element in the check shader must be mirrored.
    for elem in r.runtime_arrays.values() {
        if let Some(n) = r.names.get(elem)
            && r.structs.contains_key(elem)
            && !expected.iter().any(|(e, _, _)| e == n)
        {
            problems.push(format!(
                "{n}: in layout_check.comp but not in src/layout.rs reflection()"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "layout mismatches:\n{}",
        problems.join("\n")
    );
}

#[test]
fn constants_are_generated_from_the_header() {
    let header = include_str!("../glsl/shared/layout.glsl");
    assert!(header.contains("#define BINDING_TLAS 2"));
    assert_eq!(illum::layout::BINDING_TLAS, 2);
    assert_eq!(illum::layout::NONE, 0xffff_ffff);
    assert_eq!(illum::layout::MASK_GEOMETRY | illum::layout::MASK_LIGHTS, 3);
}
