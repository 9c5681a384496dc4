//! The five cases of the error-against-run-time sweep, built from the shipped scene files.
//!
//! | case | from | length |
//! |---|---|---|
//! | `fig4-mass-barrier` | `fig4-mass-barrier.toml` as shipped: 10 g at 2 m/s, κ 1e8, α 1.3 | 2 ms |
//! | `fig5-hammer` | `fig5-hammer-c4.toml`: C4 string, 2.97 g at 3.5 m/s, κ 4.5e9, α 2.5 | 30 ms |
//! | `soft-hammer` | `hammer-c4-soft.toml`: the same hammer at 1 m/s, η0 = 8 s⁻¹ | 30 ms |
//! | `slide-excerpt` | `slide-phrase.toml`'s string, slide and fingers (α 1.5), controls re-timed, heard as displacement | 50 ms |
//! | `stiff-hammer` | `fig5-hammer` with κ = 1e12 N/m^2.5 | 30 ms |
//!
//! The hammer cases stop after 30 ms: the strike (about 2 ms) and 28 ms of the string's response,
//! which is enough to compare the bridge force. The slide excerpt compresses the phrase's first
//! half second into 50 ms: the hand comes down from 0.3 mm above the string to 1.5 mm into it in
//! 10 ms (the slide lands on the string at about 0.25 m/s), the left finger presses 0.3 N behind
//! the slide, the right finger plucks (1.5 N, released at 20.5 ms), and from 30 ms the slide glides
//! 12 mm towards the bridge with the finger trailing 2 cm behind. Control blocks stay at
//! N_b = 64 samples at 44.1 kHz.

use std::path::Path;

use qsa_dsp::contact::PowerLaw;
use qsa_dsp::control::Breakpoints;
use qsa_dsp::scene::{OutputKind, Pickup, SlideStringParams};
use qsa_dsp::scene_file::{SceneDescription, SlideAutomation, SlideStringDescription, parse_scene};

use super::ReportError;
use super::sim::{CaseScene, Setup};

/// Simulated length of the hammer cases (s).
pub const HAMMER_SECONDS: f64 = 0.03;

/// Simulated length of the slide excerpt (s).
pub const SLIDE_SECONDS: f64 = 0.05;

/// Contact stiffness of the stiff case (N/m^α).
pub const STIFF_KAPPA: f64 = 1e12;

/// The name of the Fig. 5 hammer case (the seed's Fig. 5 values are compared on it).
pub const FIG5_HAMMER: &str = "fig5-hammer";

/// The name of the stiff hammer case (the resolution study runs on it).
pub const STIFF_HAMMER: &str = "stiff-hammer";

/// One case of the sweep.
#[derive(Debug, Clone)]
pub struct Case {
    /// Short name used in files and tables.
    pub name: &'static str,
    /// What it is, in a few words.
    pub title: &'static str,
    /// Whether it is a musical set-up (a piano or slide-guitar voice), as opposed to the paper's
    /// test bench and the stiffness extreme.
    pub musical: bool,
    /// The set-up.
    pub scene: CaseScene,
}

fn load(dir: &Path, file: &str) -> Result<SceneDescription, ReportError> {
    let path = dir.join(file);
    let text = std::fs::read_to_string(&path).map_err(|source| ReportError::Io { path: path.clone(), source })?;
    parse_scene(&text).map_err(|e| ReportError::Scene(format!("{}: {e}", path.display())))
}

fn hammer(description: &SceneDescription, law: Option<PowerLaw>) -> Result<CaseScene, ReportError> {
    let SceneDescription::HammerString(d) = description else {
        return Err(ReportError::Scene("expected a hammer-string scene".into()));
    };
    let fs = d.common.sample_rate;
    Ok(CaseScene {
        setup: Setup::Hammer(d.params),
        law: law.unwrap_or(d.common.law),
        sample_rate: fs,
        samples: (HAMMER_SECONDS * f64::from(fs)).round() as usize,
        v_ref: d.default_v_ref(),
    })
}

/// The phrase's controls re-timed into a 50 ms excerpt (see the module docs), in
/// `CONTROL_TARGETS` order.
fn excerpt_lanes(phrase: &SlideAutomation) -> Result<[Breakpoints; 6], ReportError> {
    let lane = |points: Vec<(f64, f64)>| Breakpoints::new(points).map_err(|e| ReportError::Scene(e.to_string()));
    let slide = phrase.lanes[0].at(0.0);
    let trail = slide - phrase.lanes[2].at(0.0);
    let glide = 0.012;
    Ok([
        lane(vec![(0.0, slide), (0.03, slide), (SLIDE_SECONDS, slide + glide)])?,
        lane(vec![(0.0, 0.3e-3), (0.01, -1.5e-3)])?,
        lane(vec![(0.0, slide - trail), (0.03, slide - trail), (SLIDE_SECONDS, slide - trail + glide)])?,
        lane(vec![(0.0, 0.0), (0.005, 0.0), (0.01, 0.3)])?,
        phrase.lanes[4].clone(),
        lane(vec![(0.0, 0.0), (0.015, 0.0), (0.02, 1.5), (0.0205, 0.0)])?,
    ])
}

fn slide(description: &SceneDescription) -> Result<CaseScene, ReportError> {
    let SceneDescription::SlideString(d) = description else {
        return Err(ReportError::Scene("expected a slide-string scene".into()));
    };
    let fs = d.common.sample_rate;
    let controls = SlideAutomation::new(excerpt_lanes(&d.controls)?, f64::from(fs));
    // The error is measured on the string's displacement at the pickup (the shipped scene
    // listens to its velocity, as a magnetic pickup does).
    let params = SlideStringParams { pickup: Pickup { kind: OutputKind::Displacement, ..d.params.pickup }, ..d.params };
    let excerpt = SlideStringDescription { common: d.common, params, controls: controls.clone(), body: None };
    Ok(CaseScene {
        setup: Setup::Slide(params, controls),
        law: d.common.law,
        sample_rate: fs,
        samples: (SLIDE_SECONDS * f64::from(fs)).round() as usize,
        v_ref: excerpt.default_v_ref(),
    })
}

/// The five cases, from the scene files in `scenes`.
pub fn cases(scenes: &Path) -> Result<Vec<Case>, ReportError> {
    let fig4 = match load(scenes, "fig4-mass-barrier.toml")? {
        SceneDescription::MassBarrier(d) => CaseScene {
            setup: Setup::MassBarrier(d.params),
            law: d.common.law,
            sample_rate: d.common.sample_rate,
            samples: d.common.samples,
            v_ref: d.default_v_ref(),
        },
        _ => return Err(ReportError::Scene("fig4-mass-barrier.toml: expected a mass-barrier scene".into())),
    };
    let fig5 = load(scenes, "fig5-hammer-c4.toml")?;
    let stiff = PowerLaw::new(STIFF_KAPPA, fig5.common().law.alpha()).expect("a valid law");
    Ok(vec![
        Case {
            name: "fig4-mass-barrier", title: "Fig. 4 mass–barrier (κ 1e8, α 1.3)", musical: false, scene: fig4
        },
        Case {
            name: FIG5_HAMMER,
            title: "Fig. 5 hammer–string (C4, 3.5 m/s, α 2.5)",
            musical: true,
            scene: hammer(&fig5, None)?,
        },
        Case {
            name: "soft-hammer",
            title: "soft hammer (C4, 1 m/s, η0 = 8 s⁻¹)",
            musical: true,
            scene: hammer(&load(scenes, "hammer-c4-soft.toml")?, None)?,
        },
        Case {
            name: "slide-excerpt",
            title: "slide phrase excerpt (α 1.5)",
            musical: true,
            scene: slide(&load(scenes, "slide-phrase.toml")?)?,
        },
        Case {
            name: STIFF_HAMMER,
            title: "stiff hammer (Fig. 5 with κ 1e12)",
            musical: false,
            scene: hammer(&fig5, Some(stiff))?,
        },
    ])
}
