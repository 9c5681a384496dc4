//! `cargo xtask presets`: the factory presets, one per line: id, category, name and description,
//! in the order the editor lists them. The files are `presets/<id>.toml`; `cargo xtask render
//! --midi FILE --preset ID` renders with one.
//!
//! `cargo xtask presets --vst3 DIR` also writes each as a VST3 preset file, `DIR/<name>.vstpreset`,
//! for a host's own preset browser. Such a file holds the plugin's state as the plugin saves it
//! (the VST3 SDK's preset format, below) with the parameters the preset sets: the player's
//! settings (voices, overload guard, half-pedal range) are left out unless the preset names
//! them, so loading one keeps them, as choosing the preset in the editor does.
//!
//! ```text
//! "VST3"  version (i32 = 1)  class id (32 hex digits)  offset of the chunk list (i64)
//! "Comp" data: the component's state, nice-plug's JSON {"version", "params", "fields"}
//! "List"  count (i32)  then per chunk: id (4 bytes), offset (i64), size (i64)
//! ```
//!
//! All integers are little-endian. The controller's chunk (`"Cont"`) is listed empty, as the
//! plugin itself writes it.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use qsa_dsp::instrument::{PARAMETERS, ParamKind, Preset, load_factory_presets};
use serde_json::{Map, Value, json};

/// The plugin's VST3 class id (`VST3_CLASS_ID` of the plugin crate's `Vst3Plugin`
/// implementation; a host refuses a preset file whose id is not its plugin's, which the VST3
/// host test would catch).
pub const VST3_CLASS_ID: [u8; 16] = *b"QsaStringsPlugin";

/// The plugin's version, which its saved state carries (the workspace's, as the plugin's).
const PLUGIN_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Options of `cargo xtask presets`.
#[derive(Debug, Clone, Default, Args)]
pub struct PresetsArgs {
    /// Also write every factory preset as a VST3 preset file, `DIR/<name>.vstpreset`, for a
    /// host's preset browser. Hosts look in `~/.vst3/presets/QSA Strings/QSA Strings/` (Linux),
    /// `~/Library/Audio/Presets/QSA Strings/QSA Strings/` (macOS) and `Documents\VST3
    /// Presets\QSA Strings\QSA Strings\` (Windows).
    #[arg(long, value_name = "DIR")]
    pub vst3: Option<PathBuf>,
    /// Replace preset files in DIR that differ from the ones written (without it, such a file is
    /// an error and nothing is written).
    #[arg(long, requires = "vst3")]
    pub force: bool,
}

/// Print the list to `out`, and write the VST3 preset files if asked. A preset that does not
/// parse is an error naming it.
pub fn run(args: &PresetsArgs, out: &mut dyn Write) -> Result<(), String> {
    let presets = load_factory_presets().map_err(|e| e.to_string())?;
    let id_width = presets.iter().map(|p| p.id.chars().count()).chain([2]).max().unwrap_or(2);
    let category_width = presets.iter().map(|p| p.category.chars().count()).chain([8]).max().unwrap_or(8);
    let write = |out: &mut dyn Write, line: String| writeln!(out, "{}", line.trim_end()).map_err(|e| e.to_string());
    write(out, format!("{:id_width$}  {:category_width$}  name: description", "id", "category"))?;
    for p in &presets {
        write(out, format!("{:id_width$}  {:category_width$}  {}: {}", p.id, p.category, p.name, p.description))?;
    }
    if let Some(dir) = &args.vst3 {
        let written = write_vst3_presets(&presets, dir, args.force)?;
        write(out, format!("wrote {} VST3 presets to {}", written.len(), dir.display()))?;
    }
    Ok(())
}

/// Write each of `presets` to `dir/<name>.vstpreset` (the folder made if missing). A file already
/// there with other contents is an error naming it unless `force`; then nothing is written.
/// Returns the files' paths.
pub fn write_vst3_presets(presets: &[Preset], dir: &Path, force: bool) -> Result<Vec<PathBuf>, String> {
    let files: Vec<(PathBuf, Vec<u8>)> =
        presets.iter().map(|p| (dir.join(format!("{}.vstpreset", file_name(&p.name))), vst3_preset(p))).collect();
    if !force {
        for (path, bytes) in &files {
            if path.exists() && std::fs::read(path).ok().as_deref() != Some(&bytes[..]) {
                return Err(format!("{} exists and differs; --force replaces it", path.display()));
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (path, bytes) in &files {
        std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(files.into_iter().map(|(path, _)| path).collect())
}

/// `name` as a file name on every system: the characters Windows refuses become `-`.
fn file_name(name: &str) -> String {
    name.chars().map(|c| if r#"<>:"/\|?*"#.contains(c) || c.is_control() { '-' } else { c }).collect()
}

/// The plugin's state for `preset` as nice-plug saves it: every parameter the preset sets, by id,
/// in the form its kind is saved in (`f32`, `i32`, `bool`, choices by their stable id), and the
/// preset's id in the persistent `preset` field, which the editor shows.
pub fn plugin_state(preset: &Preset) -> Value {
    let mut params = Map::new();
    for spec in PARAMETERS.iter().filter(|spec| preset.sets(spec.id)) {
        let plain = (spec.get)(&preset.values);
        let value = match spec.kind {
            ParamKind::Float { .. } => json!({ "f32": shortest(plain) }),
            ParamKind::Int { .. } => json!({ "i32": plain.round() as i32 }),
            ParamKind::Bool { .. } => json!({ "bool": plain != 0.0 }),
            ParamKind::Choice { options, .. } => {
                let (id, _) = options[(plain.round().max(0.0) as usize).min(options.len() - 1)];
                json!({ "string": id })
            }
        };
        params.insert(spec.id.to_owned(), value);
    }
    // A persistent field holds its value serialised as JSON text.
    let id = serde_json::to_string(&preset.id).unwrap_or_default();
    json!({ "version": PLUGIN_VERSION, "params": params, "fields": { "preset": id } })
}

/// `x` as the `f64` whose shortest text is `x`'s (0.92, not 0.9200000166893005), as nice-plug
/// writes an `f32`: read back as an `f32`, it is `x` again.
fn shortest(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// The VST3 preset file of `preset` (module docs).
pub fn vst3_preset(preset: &Preset) -> Vec<u8> {
    const HEADER: usize = 4 + 4 + 32 + 8;
    let state = plugin_state(preset).to_string().into_bytes();
    let list_offset = (HEADER + state.len()) as i64;
    let mut file = Vec::with_capacity(HEADER + state.len() + 8 + 2 * 20);
    file.extend_from_slice(b"VST3");
    file.extend_from_slice(&1i32.to_le_bytes());
    file.extend(VST3_CLASS_ID.iter().flat_map(|b| format!("{b:02X}").into_bytes()));
    file.extend_from_slice(&list_offset.to_le_bytes());
    file.extend_from_slice(&state);
    file.extend_from_slice(b"List");
    file.extend_from_slice(&2i32.to_le_bytes());
    for (id, offset, size) in [(b"Comp", HEADER as i64, state.len() as i64), (b"Cont", list_offset, 0)] {
        file.extend_from_slice(id);
        file.extend_from_slice(&offset.to_le_bytes());
        file.extend_from_slice(&size.to_le_bytes());
    }
    file
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsa_dsp::instrument::{PLAYER_SETTINGS, find_preset, parse_preset};

    /// The file's header, chunk list and chunks lie where the VST3 SDK reads them: the class id's
    /// 32 hex digits, the list at the offset the header gives, the component chunk holding the
    /// state's JSON and an empty controller chunk after it.
    #[test]
    fn a_vst3_preset_file_is_laid_out_as_the_sdk_reads_it() {
        let preset = find_preset("lap-steel").unwrap();
        let file = vst3_preset(preset);
        let int = |at: usize| i64::from_le_bytes(file[at..at + 8].try_into().unwrap());
        assert_eq!(&file[..4], b"VST3");
        assert_eq!(i32::from_le_bytes(file[4..8].try_into().unwrap()), 1);
        assert_eq!(&file[8..40], b"517361537472696E6773506C7567696E", "the class id \"QsaStringsPlugin\" in hex");
        let list = int(40) as usize;
        assert_eq!(&file[list..list + 4], b"List");
        assert_eq!(i32::from_le_bytes(file[list + 4..list + 8].try_into().unwrap()), 2);
        let chunk =
            |k: usize| (&file[list + 8 + 20 * k..list + 12 + 20 * k], int(list + 12 + 20 * k), int(list + 20 + 20 * k));
        let (id, offset, size) = chunk(0);
        assert_eq!((id, offset), (&b"Comp"[..], 48));
        let state: Value = serde_json::from_slice(&file[48..48 + size as usize]).unwrap();
        assert_eq!(state, plugin_state(preset));
        assert_eq!(chunk(1), (&b"Cont"[..], list as i64, 0));
        assert_eq!(file.len(), list + 8 + 40, "nothing after the list");
    }

    /// The state holds every parameter but the player's settings, each in the form nice-plug
    /// saves its kind in, with the preset's values (the lap steel's slide mass 120 g, its hand
    /// -2.5 mm, the slide mode by its id), and the preset's id in the `preset` field; a preset
    /// naming the voices holds them.
    #[test]
    fn the_state_holds_what_the_preset_sets_and_not_the_players_settings() {
        let preset = find_preset("lap-steel").unwrap();
        let state = plugin_state(preset);
        let params = state["params"].as_object().unwrap();
        assert_eq!(params.len(), PARAMETERS.len() - PLAYER_SETTINGS.len());
        for id in PLAYER_SETTINGS {
            assert!(!params.contains_key(id), "{id} left out");
        }
        assert_eq!(params["smass"], json!({ "f32": 120.0 }));
        assert_eq!(params["hand"], json!({ "f32": -2.5 }));
        assert_eq!(params["mode"], json!({ "string": "slide" }));
        assert_eq!(params["nb"], json!({ "i32": 64 }));
        assert_eq!(params["limit"], json!({ "bool": true }));
        assert_eq!(params["pluck"], json!({ "f32": 0.92 }), "as nice-plug writes an f32");
        assert_eq!(params["kappa"], json!({ "f32": 5e10 }));
        assert_eq!(state["fields"]["preset"], json!("\"lap-steel\""));
        assert_eq!(state["version"], json!(PLUGIN_VERSION));

        let text = "name = \"Big\"\ncategory = \"Piano\"\ndescription = \"d\"\n[params]\nvoices = 96\n";
        let naming = plugin_state(&parse_preset("big", text).unwrap());
        assert_eq!(naming["params"]["voices"], json!({ "i32": 96 }));
        assert!(naming["params"].get("guard").is_none());
    }

    /// Writing makes one file per preset under its name; writing again changes nothing; a file
    /// of the same name with other contents stops the writing unless forced, and is then
    /// replaced.
    #[test]
    fn preset_files_are_written_once_and_a_different_file_is_replaced_only_when_forced() {
        let dir = std::env::temp_dir().join(format!("qsa-vst3-presets-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let presets = load_factory_presets().unwrap();
        let written = write_vst3_presets(&presets, &dir, false).unwrap();
        assert_eq!(written.len(), presets.len());
        assert!(written.iter().any(|p| p.ends_with("Lap steel.vstpreset")));
        assert_eq!(write_vst3_presets(&presets, &dir, false).unwrap(), written, "the same files again");
        let mine = dir.join("Lap steel.vstpreset");
        std::fs::write(&mine, b"the user's own").unwrap();
        let refused = write_vst3_presets(&presets, &dir, false).unwrap_err();
        assert!(refused.contains("Lap steel.vstpreset exists and differs"), "{refused}");
        assert_eq!(std::fs::read(&mine).unwrap(), b"the user's own", "kept");
        write_vst3_presets(&presets, &dir, true).unwrap();
        assert_eq!(std::fs::read(&mine).unwrap(), vst3_preset(find_preset("lap-steel").unwrap()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn file_names_keep_only_characters_every_system_takes() {
        assert_eq!(file_name("A/B: c?"), "A-B- c-");
        assert_eq!(file_name("Lap steel"), "Lap steel");
    }
}
