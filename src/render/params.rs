//! An integrator's parameters as given: name → text, each with where it came from (a command-line
//! option, a scene file's field, an API call), so that an integrator parses its own and names the
//! origin of a value it cannot read or a name it does not take (as pbrt-v4's ParameterDictionary
//! and `ReportUnused`).

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::str::FromStr;

#[derive(Clone, Debug, PartialEq)]
struct Value {
    text: String,
    /// E.g. `--light-samples`, `scene.json: integrator.light_samples`.
    origin: String,
}

/// Parameters by name; a later [`Params::set`] of a name replaces the earlier one.
#[derive(Clone, Debug, Default)]
pub struct Params {
    values: BTreeMap<String, Value>,
    read: RefCell<Vec<String>>,
}

impl Params {
    pub fn new() -> Params {
        Params::default()
    }

    /// Sets `name` to `text`, which came from `origin`.
    pub fn set(&mut self, name: &str, text: impl Into<String>, origin: impl Into<String>) {
        self.values.insert(
            name.to_string(),
            Value {
                text: text.into(),
                origin: origin.into(),
            },
        );
    }

    fn take(&self, name: &str) -> Option<&Value> {
        self.read.borrow_mut().push(name.to_string());
        self.values.get(name)
    }

    /// Parameter `name` read as a `T`, else `default` when it is not given.
    pub fn get<T: FromStr>(&self, name: &str, default: T) -> Result<T, String>
    where
        T::Err: std::fmt::Display,
    {
        match self.take(name) {
            None => Ok(default),
            Some(v) => v
                .text
                .trim()
                .parse()
                .map_err(|e| format!("{}: {name} = {:?}: {e}", v.origin, v.text)),
        }
    }

    /// Whether `name` is given (without reading it).
    pub fn has(&self, name: &str) -> bool {
        self.values.contains_key(name)
    }

    /// A switch: on/off (true/false also taken).
    pub fn get_switch(&self, name: &str, default: bool) -> Result<bool, String> {
        match self.take(name) {
            None => Ok(default),
            Some(v) => match v.text.trim() {
                "on" | "true" => Ok(true),
                "off" | "false" => Ok(false),
                t => Err(format!("{}: {name} = {t:?}: expected on or off", v.origin)),
            },
        }
    }

    /// The names given that no `get` asked for, with their origins.
    pub fn unread(&self) -> Vec<(String, String)> {
        let read = self.read.borrow();
        self.values
            .iter()
            .filter(|(k, _)| !read.contains(k))
            .map(|(k, v)| (k.clone(), v.origin.clone()))
            .collect()
    }

    /// Fails naming every parameter that `integrator` did not read, and the ones it takes.
    pub fn finish(&self, integrator: &str, takes: &[&str]) -> Result<(), String> {
        let unread = self.unread();
        if unread.is_empty() {
            return Ok(());
        }
        let names: Vec<String> = unread.iter().map(|(k, o)| format!("{k} ({o})")).collect();
        Err(format!(
            "the {integrator} integrator takes no parameter {}; it takes: {}",
            names.join(", "),
            takes.join(", ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_parsed_and_named_with_their_origin() {
        let mut p = Params::new();
        p.set("n", "7", "--n");
        p.set("x", "seven", "scene.json: integrator.x");
        p.set("s", "off", "--s");
        assert_eq!(p.get("n", 1u32), Ok(7));
        assert_eq!(p.get("absent", 3i32), Ok(3));
        assert_eq!(p.get_switch("s", true), Ok(false));
        let e = p.get("x", 0u32).unwrap_err();
        assert!(
            e.contains("scene.json: integrator.x") && e.contains("seven"),
            "{e}"
        );
        assert!(p.finish("t", &["n"]).is_ok());
    }

    #[test]
    fn unread_names_are_refused() {
        let mut p = Params::new();
        p.set("max_depth", "3", "--max-depth");
        p.set("n", "1", "--n");
        p.get("n", 0u32).unwrap();
        let e = p.finish("direct", &["n"]).unwrap_err();
        assert!(
            e.contains("direct") && e.contains("max_depth (--max-depth)") && !e.contains("n ("),
            "{e}"
        );
        // A later value of a name replaces the earlier one (options over the scene's section).
        p.set("n", "2", "api");
        assert_eq!(p.get("n", 0u32), Ok(2));
    }
}
