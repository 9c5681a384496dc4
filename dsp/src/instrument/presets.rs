//! Factory presets: named sets of parameter values, one readable TOML file each in the
//! repository's `presets/` folder, embedded in the build.
//!
//! A preset file (`presets/<id>.toml`; the id is the file name):
//!
//! ```toml
//! name = "Concert grand"                  # shown in the editor
//! category = "Piano"                      # one of CATEGORIES
//! description = "A full, long-ringing grand: ..."   # one line
//!
//! [params]                                # plugin parameter ids, in the units `--set` takes
//! mode = "piano"                          # choices by name
//! hard = 1.4                              # numbers in the parameter's unit (×, ms, mm, g, ...)
//! gain = -3.0                             # gain in dB
//! follow = true                           # switches: true/false or "on"/"off"
//! ```
//!
//! A parameter the preset leaves out takes its default ([`ParamValues::default`]), so a preset
//! sets every parameter but the player's settings ([`PLAYER_SETTINGS`]: voices, the overload
//! guard and the half pedal's zone), which it sets only when it names them ([`Preset::sets`]).
//! Unknown keys, unknown parameter ids, values of the wrong kind or outside the parameter's range
//! are errors naming the preset and the key; nothing here panics.

use std::sync::OnceLock;

use crate::instrument::params::{PLAYER_SETTINGS, ParamError, ParamValues};

/// Preset categories, in the order the editor lists them.
pub const CATEGORIES: [&str; 4] = ["Paper", "Piano", "Slide", "Contact"];

/// The factory presets as `(id, TOML text)`, embedded at compile time from `presets/<id>.toml`,
/// in the order the editor lists them (by category, then as here).
pub const FACTORY_PRESETS: [(&str, &str); 21] = [
    ("fig5-hammer", include_str!("../../../presets/fig5-hammer.toml")),
    ("fig5-hammer-imp", include_str!("../../../presets/fig5-hammer-imp.toml")),
    ("soft-hammer", include_str!("../../../presets/soft-hammer.toml")),
    ("slide-phrase", include_str!("../../../presets/slide-phrase.toml")),
    ("concert-grand", include_str!("../../../presets/concert-grand.toml")),
    ("felt-piano", include_str!("../../../presets/felt-piano.toml")),
    ("bright-piano", include_str!("../../../presets/bright-piano.toml")),
    ("dark-piano", include_str!("../../../presets/dark-piano.toml")),
    ("upright", include_str!("../../../presets/upright.toml")),
    ("tack-piano", include_str!("../../../presets/tack-piano.toml")),
    ("bell-strings", include_str!("../../../presets/bell-strings.toml")),
    ("bottleneck", include_str!("../../../presets/bottleneck.toml")),
    ("lap-steel", include_str!("../../../presets/lap-steel.toml")),
    ("dobro-rattle", include_str!("../../../presets/dobro-rattle.toml")),
    ("acoustic-slide", include_str!("../../../presets/acoustic-slide.toml")),
    ("parked-slide", include_str!("../../../presets/parked-slide.toml")),
    ("modwheel-slide", include_str!("../../../presets/modwheel-slide.toml")),
    ("stiff-slide", include_str!("../../../presets/stiff-slide.toml")),
    ("soft-slide", include_str!("../../../presets/soft-slide.toml")),
    ("steel-hammer", include_str!("../../../presets/steel-hammer.toml")),
    ("cotton-hammer", include_str!("../../../presets/cotton-hammer.toml")),
];

/// A parsed preset.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    /// Stable id: the file name without `.toml`.
    pub id: String,
    /// Display name.
    pub name: String,
    /// One of [`CATEGORIES`].
    pub category: String,
    /// One line on what it shows.
    pub description: String,
    /// Every parameter's value: the preset's, or the default where it says nothing.
    pub values: ParamValues,
    /// The player's settings ([`PLAYER_SETTINGS`]) the file names, and so sets.
    player_settings: Vec<&'static str>,
}

impl Preset {
    /// Whether choosing this preset sets parameter `id`: every parameter but a player's setting
    /// ([`PLAYER_SETTINGS`]) that the file leaves out, which stays as the player set it.
    pub fn sets(&self, id: &str) -> bool {
        !PLAYER_SETTINGS.contains(&id) || self.player_settings.contains(&id)
    }

    /// The first parameter it sets whose value in `values` differs from the preset's (within
    /// [`ParamValues::first_difference`]'s tolerance), or `None` when `values` still sound as
    /// the preset.
    pub fn first_difference(&self, values: &ParamValues) -> Option<&'static str> {
        values.first_difference_among(&self.values, |id| self.sets(id))
    }
}

/// Why a preset file was refused. Every message names the preset.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PresetError {
    /// Not TOML.
    #[error("preset {id}: not valid TOML: {message}")]
    Syntax {
        /// The preset id.
        id: String,
        /// The parser's message.
        message: String,
    },
    /// A key that must be there is missing.
    #[error("preset {id}: missing `{key}`")]
    Missing {
        /// The preset id.
        id: String,
        /// The missing key.
        key: &'static str,
    },
    /// A top-level key the format does not have.
    #[error("preset {id}: unknown key `{key}` (the keys are name, category, description and [params])")]
    UnknownKey {
        /// The preset id.
        id: String,
        /// The key.
        key: String,
    },
    /// A key holds the wrong kind of value.
    #[error("preset {id}: `{key}` must be {expected}")]
    WrongType {
        /// The preset id.
        id: String,
        /// The key.
        key: String,
        /// What it must be.
        expected: &'static str,
    },
    /// A category not in [`CATEGORIES`].
    #[error("preset {id}: category \"{category}\" is not one of {known}", known = CATEGORIES.join(", "))]
    Category {
        /// The preset id.
        id: String,
        /// The category given.
        category: String,
    },
    /// An unknown parameter id, a value that does not parse for it or one outside its range.
    #[error("preset {id}: [params] {source}")]
    Param {
        /// The preset id.
        id: String,
        /// What the parameter said.
        source: ParamError,
    },
}

/// Parse the preset file `text` with id `id`.
pub fn parse_preset(id: &str, text: &str) -> Result<Preset, PresetError> {
    let table: toml::Table = text.parse().map_err(|e: toml::de::Error| PresetError::Syntax {
        id: id.to_owned(),
        message: e.to_string().trim().into(),
    })?;
    let text_field = |key: &'static str| -> Result<String, PresetError> {
        let value = table.get(key).ok_or(PresetError::Missing { id: id.to_owned(), key })?;
        let text = value.as_str().map(str::trim).filter(|s| !s.is_empty() && !s.contains('\n'));
        let wrong = || PresetError::WrongType { id: id.to_owned(), key: key.into(), expected: "a one-line string" };
        text.map(str::to_owned).ok_or_else(wrong)
    };
    for key in table.keys() {
        if !["name", "category", "description", "params"].contains(&key.as_str()) {
            return Err(PresetError::UnknownKey { id: id.to_owned(), key: key.clone() });
        }
    }
    let name = text_field("name")?;
    let category = text_field("category")?;
    let description = text_field("description")?;
    if !CATEGORIES.contains(&category.as_str()) {
        return Err(PresetError::Category { id: id.to_owned(), category });
    }
    let empty = toml::Table::new();
    let params = match table.get("params") {
        None => &empty,
        Some(toml::Value::Table(t)) => t,
        Some(_) => {
            return Err(PresetError::WrongType { id: id.to_owned(), key: "params".into(), expected: "a table" });
        }
    };
    let mut values = ParamValues::default();
    let player_settings = PLAYER_SETTINGS.into_iter().filter(|id| params.contains_key(*id)).collect();
    for (key, value) in params {
        let text = match value {
            toml::Value::String(s) => s.clone(),
            toml::Value::Integer(i) => i.to_string(),
            toml::Value::Float(f) => f.to_string(),
            toml::Value::Boolean(b) => (if *b { "on" } else { "off" }).to_owned(),
            _ => {
                return Err(PresetError::WrongType {
                    id: id.to_owned(),
                    key: format!("params.{key}"),
                    expected: "a number, a string or true/false",
                });
            }
        };
        values.set(key, &text).map_err(|source| PresetError::Param { id: id.to_owned(), source })?;
    }
    Ok(Preset { id: id.to_owned(), name, category, description, values, player_settings })
}

/// Every factory preset, parsed, or the first error.
pub fn load_factory_presets() -> Result<Vec<Preset>, PresetError> {
    FACTORY_PRESETS.iter().map(|(id, text)| parse_preset(id, text)).collect()
}

/// The factory presets, parsed once, in [`FACTORY_PRESETS`] order. A file that failed to parse
/// would be left out rather than stop the plugin (the tests make sure none does).
pub fn factory_presets() -> &'static [Preset] {
    static PRESETS: OnceLock<Vec<Preset>> = OnceLock::new();
    PRESETS.get_or_init(|| FACTORY_PRESETS.iter().filter_map(|(id, text)| parse_preset(id, text).ok()).collect())
}

/// The factory preset called `name`: its id, or its display name (case-insensitive).
pub fn find_preset(name: &str) -> Option<&'static Preset> {
    let name = name.trim();
    let presets = factory_presets();
    presets.iter().find(|p| p.id == name).or_else(|| presets.iter().find(|p| p.name.eq_ignore_ascii_case(name)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instrument::settings::Mode;

    const GOOD: &str = r#"
name = "Test"
category = "Piano"
description = "A test preset."

[params]
hard = 2.5
segs = 13
gain = -6
follow = false
solver = "imp"
"#;

    #[test]
    fn a_preset_sets_what_it_names_and_defaults_the_rest() {
        let p = parse_preset("test", GOOD).unwrap();
        assert_eq!((p.id.as_str(), p.name.as_str(), p.category.as_str()), ("test", "Test", "Piano"));
        let d = ParamValues::default();
        assert_eq!(p.values.hardness, 2.5);
        assert_eq!(p.values.segments, 13);
        assert!((p.values.gain - 0.501_187).abs() < 1e-5, "gain is in dB: {}", p.values.gain);
        assert!(!p.values.follow_key);
        assert_eq!(p.values.method, crate::contact::Method::Imp);
        assert_eq!(p.values.mode, Mode::Piano);
        let untouched = ParamValues { hardness: d.hardness, segments: d.segments, gain: d.gain, ..p.values };
        assert_eq!(untouched, ParamValues { follow_key: false, method: p.values.method, ..d });
    }

    /// A preset sets every parameter (`hard`, named, and `nb`, defaulted) but a player's setting
    /// it leaves out; one naming the voice count sets it and still leaves the guard. Compared with
    /// the preset, only what it sets counts.
    #[test]
    fn a_preset_sets_the_players_settings_only_when_it_names_them() {
        let plain = parse_preset("test", GOOD).unwrap();
        assert!(plain.sets("hard") && plain.sets("nb"));
        assert!(!plain.sets("voices") && !plain.sets("guard"));
        let naming = parse_preset("test", &format!("{GOOD}voices = 96\n")).unwrap();
        assert!(naming.sets("voices") && !naming.sets("guard"));
        assert_eq!(naming.values.voices, 96);

        let player = ParamValues { voices: 7, overload_guard: false, ..plain.values };
        assert_eq!(plain.first_difference(&player), None, "the player's settings are not the preset's");
        assert_eq!(naming.first_difference(&player), Some("voices"));
        assert_eq!(plain.first_difference(&ParamValues { block: 8, ..player }), Some("nb"));
    }

    #[test]
    fn bad_presets_are_errors_naming_the_key() {
        let head = "name = \"x\"\ncategory = \"Piano\"\ndescription = \"d\"\n";
        let param = |line: &str| format!("{head}[params]\n{line}");
        let cases = [
            (param("kapa = 1"), "[params] unknown parameter id \"kapa\" (one of: mode, solver"),
            (param("hard = \"soft\""), "[params] hard: cannot use \"soft\" (a finite number)"),
            (param("hard = 20"), "[params] hard = 20 is outside the parameter's range 0.1..=10×"),
            (param("pluck = 0.3"), "[params] pluck = 0.3 is outside the parameter's range 0.5..=0.98"),
            (param("segs = 65"), "[params] segs = 65 is outside the parameter's range 1..=64"),
            (param("segs = 6.5"), "[params] segs: cannot use \"6.5\" (a whole number)"),
            (param("gain = 20"), "[params] gain = 20 is outside the parameter's range -36..=12 dB"),
            (param("mode = \"banjo\""), "[params] mode: cannot use \"banjo\" (piano or slide)"),
            (param("hard = [1]"), "`params.hard` must be a number, a string or true/false"),
            (format!("{head}params = 3"), "`params` must be a table"),
            ("name = \"x\"\ncategory = \"Harp\"\ndescription = \"d\"".into(), "category \"Harp\" is not one of Paper"),
            ("name = \"x\"\ncategory = \"Piano\"".into(), "missing `description`"),
            ("name = \"\"\ncategory = \"Piano\"\ndescription = \"d\"".into(), "`name` must be a one-line string"),
            (format!("{head}colour = 1"), "unknown key `colour`"),
            ("name = \"x\n".into(), "not valid TOML"),
        ];
        for (text, expected) in cases {
            let message = parse_preset("bad", &text).expect_err(&text).to_string();
            assert!(message.starts_with("preset bad: "), "{message}");
            assert!(message.contains(expected), "{message:?} should contain {expected:?}");
        }
        // At the top of a range is in range, even where f32 rounds above it (0.98 as f32 > 0.98).
        for line in ["pluck = 0.98", "kappa = 1e13", "glide = 2000", "hand = -3", "gain = 12", "segs = 64"] {
            parse_preset("edge", &param(line)).unwrap_or_else(|e| panic!("{line}: {e}"));
        }
    }

    /// Every file in `presets/` is embedded (none forgotten), every embedded preset parses, ids
    /// are unique and match their files, names are unique, and there are at least 16, in every
    /// category.
    #[test]
    fn every_preset_file_is_embedded_and_parses() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
        let mut files: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|f| f.ends_with(".toml"))
            .collect();
        files.sort();
        let mut embedded: Vec<String> = FACTORY_PRESETS.iter().map(|(id, _)| format!("{id}.toml")).collect();
        embedded.sort();
        assert_eq!(files, embedded, "presets/ and FACTORY_PRESETS list the same files");
        for (id, text) in FACTORY_PRESETS {
            let on_disk = std::fs::read_to_string(dir.join(format!("{id}.toml"))).unwrap();
            assert_eq!(on_disk, text, "{id}: the embedded text is the file's");
        }
        let presets = load_factory_presets().unwrap_or_else(|e| panic!("{e}"));
        assert!(presets.len() >= 16, "{} presets", presets.len());
        assert_eq!(factory_presets(), &presets[..]);
        let mut ids: Vec<&str> = presets.iter().map(|p| p.id.as_str()).collect();
        let mut names: Vec<String> = presets.iter().map(|p| p.name.to_lowercase()).collect();
        ids.sort();
        ids.dedup();
        names.sort();
        names.dedup();
        assert_eq!((ids.len(), names.len()), (presets.len(), presets.len()), "ids and names are unique");
        for category in CATEGORIES {
            assert!(presets.iter().any(|p| p.category == category), "no preset in {category}");
        }
        // Listed by category, as the editor shows them.
        let order: Vec<usize> =
            presets.iter().map(|p| CATEGORIES.iter().position(|c| *c == p.category).unwrap()).collect();
        assert!(order.windows(2).all(|w| w[0] <= w[1]), "FACTORY_PRESETS is grouped by category");
    }

    /// Every key of every factory preset's `[params]` is a parameter id of the table.
    #[test]
    fn every_preset_key_is_a_parameter_id() {
        for (id, text) in FACTORY_PRESETS {
            let table: toml::Table = text.parse().unwrap();
            let params = table.get("params").and_then(toml::Value::as_table).cloned().unwrap_or_default();
            for key in params.keys() {
                assert!(crate::instrument::params::param_spec(key).is_some(), "{id}: {key} is not a parameter id");
            }
        }
    }

    #[test]
    fn presets_are_found_by_id_or_name() {
        assert_eq!(find_preset("lap-steel").map(|p| p.id.as_str()), Some("lap-steel"));
        let name = factory_presets()[0].name.to_uppercase();
        assert_eq!(find_preset(&name).map(|p| p.id.as_str()), Some(factory_presets()[0].id.as_str()));
        assert!(find_preset("banjo").is_none());
    }
}
