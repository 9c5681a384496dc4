//! Scene-file tables of the `mass-barrier` scene: a point mass striking a rigid barrier.
//!
//! ```toml
//! [mass]                      # mass-barrier
//! mass = 0.01                 # kg
//! u0 = -1e-3                  # m, initial displacement
//! v0 = 2.0                    # m/s, initial velocity (towards the barrier when positive)
//!
//! [barrier]
//! position = 0.0              # m
//! ```

use serde::Deserialize;

use super::error::SceneError;
use super::tables::{Common, ContactTable, Head, OutputTable, SolverTable, common, finite, mass};
use crate::scene::MassBarrierParams;

/// A validated mass–barrier scene.
#[derive(Debug, Clone, PartialEq)]
pub struct MassBarrierDescription {
    /// Common settings.
    pub common: Common,
    /// The mass and barrier.
    pub params: MassBarrierParams,
}

impl MassBarrierDescription {
    /// The default QSA reference energy: everything the scene can put into the contact, the
    /// initial kinetic energy plus any initial compression energy (J). A scene that starts at
    /// rest out of contact never touches; its fit then spans 1 mm.
    pub fn default_v_ref(&self) -> f64 {
        let law = &self.common.law;
        let y0 = self.params.u0 - self.params.barrier;
        let energy = self.params.max_contact_energy() + law.potential(y0);
        if energy > 0.0 { energy } else { law.potential(1e-3) }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MassBarrierFile {
    /// Checked before the typed parse.
    #[allow(dead_code)]
    version: Option<i64>,
    /// Checked before the typed parse.
    #[allow(dead_code)]
    scene: String,
    sample_rate: f64,
    duration: f64,
    solver: SolverTable,
    contact: ContactTable,
    mass: MassTable,
    barrier: BarrierTable,
    #[serde(default)]
    output: OutputTable,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MassTable {
    mass: f64,
    u0: f64,
    v0: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BarrierTable {
    position: f64,
}

impl MassBarrierFile {
    pub(super) fn validate(self) -> Result<MassBarrierDescription, SceneError> {
        let head = Head { sample_rate: self.sample_rate, duration: self.duration };
        let common = common(&head, &self.solver, &self.contact, None, &self.output)?;
        let params = MassBarrierParams {
            mass: mass("mass.mass", self.mass.mass)?,
            u0: finite("mass.u0", self.mass.u0)?,
            v0: finite("mass.v0", self.mass.v0)?,
            barrier: finite("barrier.position", self.barrier.position)?,
        };
        Ok(MassBarrierDescription { common, params })
    }
}
