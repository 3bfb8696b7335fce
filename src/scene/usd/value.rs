//! USD attribute values as the numbers illum reads: each helper takes any precision USD authors
//! (half, float, double; int where a number is meant) and returns None for another type.

use openusd::sdf::Value;

pub fn scalar(v: &Value) -> Option<f64> {
    Some(match v {
        Value::Double(d) => *d,
        Value::Float(f) => f64::from(*f),
        Value::Half(h) => f64::from(h.to_f32()),
        Value::Int(i) => f64::from(*i),
        Value::Int64(i) => *i as f64,
        Value::Uint(i) => f64::from(*i),
        _ => return None,
    })
}

pub fn boolean(v: &Value) -> Option<bool> {
    match v {
        Value::Bool(b) => Some(*b),
        Value::Int(i) => Some(*i != 0),
        _ => None,
    }
}

pub fn token(v: &Value) -> Option<&str> {
    match v {
        Value::Token(t) => Some(t.as_str()),
        Value::String(s) => Some(s.as_str()),
        _ => None,
    }
}

pub fn vec3(v: &Value) -> Option<[f64; 3]> {
    Some(match v {
        Value::Vec3d(a) => [a.x, a.y, a.z],
        Value::Vec3f(a) => [a.x, a.y, a.z].map(f64::from),
        Value::Vec3h(a) => [a.x, a.y, a.z].map(|c| f64::from(c.to_f32())),
        _ => return None,
    })
}

pub fn vec2(v: &Value) -> Option<[f64; 2]> {
    Some(match v {
        Value::Vec2d(a) => [a.x, a.y],
        Value::Vec2f(a) => [a.x, a.y].map(f64::from),
        Value::Vec2h(a) => [a.x, a.y].map(|c| f64::from(c.to_f32())),
        Value::Vec2i(a) => [a.x, a.y].map(f64::from),
        _ => return None,
    })
}

pub fn vec3_array(v: &Value) -> Option<Vec<[f64; 3]>> {
    Some(match v {
        Value::Vec3dVec(a) => a.iter().map(|a| [a.x, a.y, a.z]).collect(),
        Value::Vec3fVec(a) => a.iter().map(|a| [a.x, a.y, a.z].map(f64::from)).collect(),
        Value::Vec3hVec(a) => a
            .iter()
            .map(|a| [a.x, a.y, a.z].map(|c| f64::from(c.to_f32())))
            .collect(),
        _ => return None,
    })
}

pub fn vec2_array(v: &Value) -> Option<Vec<[f64; 2]>> {
    Some(match v {
        Value::Vec2dVec(a) => a.iter().map(|a| [a.x, a.y]).collect(),
        Value::Vec2fVec(a) => a.iter().map(|a| [a.x, a.y].map(f64::from)).collect(),
        Value::Vec2hVec(a) => a
            .iter()
            .map(|a| [a.x, a.y].map(|c| f64::from(c.to_f32())))
            .collect(),
        _ => return None,
    })
}

pub fn int_array(v: &Value) -> Option<Vec<i64>> {
    Some(match v {
        Value::IntVec(a) => a.iter().map(|&i| i64::from(i)).collect(),
        Value::Int64Vec(a) => a.clone(),
        Value::UintVec(a) => a.iter().map(|&i| i64::from(i)).collect(),
        _ => return None,
    })
}

pub fn token_array(v: &Value) -> Option<Vec<String>> {
    match v {
        Value::TokenVec(a) => Some(a.iter().map(|t| t.as_str().to_string()).collect()),
        Value::StringVec(a) => Some(a.clone()),
        _ => None,
    }
}

/// A short rendering of a value for error messages: numbers and vectors as written in USD,
/// arrays by their first values and length.
pub fn show(v: &Value) -> String {
    let num = |x: f64| format!("{x}");
    let tuple = |c: &[f64]| {
        format!(
            "({})",
            c.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ")
        )
    };
    let list = |items: Vec<String>| {
        let n = items.len();
        let head: Vec<String> = items.into_iter().take(3).collect();
        format!(
            "[{}{}] ({n} values)",
            head.join(", "),
            if n > 3 { ", …" } else { "" }
        )
    };
    if let Some(x) = scalar(v) {
        return num(x);
    }
    if let Some(c) = vec3(v) {
        return tuple(&c);
    }
    if let Some(c) = vec2(v) {
        return tuple(&c);
    }
    if let Some(t) = token(v) {
        return format!("{t:?}");
    }
    if let Some(a) = vec3_array(v) {
        return list(a.iter().map(|c| tuple(c)).collect());
    }
    if let Some(a) = vec2_array(v) {
        return list(a.iter().map(|c| tuple(c)).collect());
    }
    if let Some(a) = int_array(v) {
        return list(a.iter().map(i64::to_string).collect());
    }
    let s = format!("{v:?}");
    if s.chars().count() > 80 {
        format!("{}…", s.chars().take(77).collect::<String>())
    } else {
        s
    }
}
