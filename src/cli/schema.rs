//! `illum schema`: the JSON Schema of the scene format.

use anyhow::Result;

pub fn run() -> Result<()> {
    println!(
        "{}",
        serde_json::to_string_pretty(&crate::scene::json_schema())?
    );
    Ok(())
}
