//! `cargo xtask presets`: the factory presets, one per line: id, category, name and description,
//! in the order the editor lists them. The files are `presets/<id>.toml`; `cargo xtask render
//! --midi FILE --preset ID` renders with one.

use std::io::Write;

use qsa_dsp::instrument::load_factory_presets;

/// Print the list to `out`. A preset that does not parse is an error naming it.
pub fn run(out: &mut dyn Write) -> Result<(), String> {
    let presets = load_factory_presets().map_err(|e| e.to_string())?;
    let id_width = presets.iter().map(|p| p.id.chars().count()).chain([2]).max().unwrap_or(2);
    let category_width = presets.iter().map(|p| p.category.chars().count()).chain([8]).max().unwrap_or(8);
    let write = |out: &mut dyn Write, line: String| writeln!(out, "{}", line.trim_end()).map_err(|e| e.to_string());
    write(out, format!("{:id_width$}  {:category_width$}  name: description", "id", "category"))?;
    for p in &presets {
        write(out, format!("{:id_width$}  {:category_width$}  {}: {}", p.id, p.category, p.name, p.description))?;
    }
    Ok(())
}
