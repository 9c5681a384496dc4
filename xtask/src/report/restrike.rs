//! Repeated strikes on one piano string, as the instrument's piano voice plays them: the hammer
//! thrown again at a string that still swings, and a damper landing, perhaps during a contact.
//!
//! Each strike throws a fresh hammer from just beyond where the string is under it
//! ([`HammerCore::strike`]) and refits QSA over the hammer's kinetic energy plus the string's
//! energy, as `PianoVoice::play` does, or ([`VrefRule::Incoming`]) over the hammer's kinetic
//! energy alone: on a string that swings the compression can then outgrow the fit, and QSA
//! works on its last segment extended beyond the last knot. The damper lands as the voice's does: its rate at the
//! fundamental rises towards its target with a time constant, and every [`DAMPER_UPDATE`] the
//! modes' extra decay rates `D·g_i` ([`damper_shares`]) are set anew.
//!
//! # The energy account
//!
//! Two things put energy in from outside the scheme, and each is booked as work done on the
//! system (the frames' `control_work`), so that `energy + losses − control_work` stays constant
//! to rounding:
//! - a strike replaces the hammer: the action throws the new one (its kinetic energy comes in)
//!   and catches the old one (whatever it still carried leaves, with the felt's compression if
//!   it still pressed on the string);
//! - a change of the string's decay rates changes the scheme's modal stiffness
//!   `K̂_i = (4m̃/Δt²)(1 − 2P_i + Q_i)/(1 + 2P_i + Q_i)` (docs/physics.md §6.5), so the numerical
//!   energy of an unchanged state moves by a little: that change is the work of the parameter
//!   change.

use qsa_dsp::contact::{Method, PowerLaw, QuadSpline};
use qsa_dsp::exciter::HammerParams;
use qsa_dsp::instrument::{DAMPER_UPDATE, Solvers, damper_shares};
use qsa_dsp::scene::{Frame, HammerCore, HammerStringParams, OutputKind, Pickup};
use qsa_dsp::string::{ModalString, StringParams};

/// Highest mode frequency of the voice's strings (Hz), as the instrument prepares them.
pub const MAX_FREQUENCY: f64 = 20_000.0;

/// A damper landing: when it starts (sample), its rate at the fundamental (1/s) and how fast it
/// settles (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damper {
    /// Sample at which the key is released.
    pub at: usize,
    /// Target decay rate at the fundamental, `D` (1/s).
    pub rate: f64,
    /// Time constant of the felt settling (s).
    pub time: f64,
}

/// The reference energy V_ref (J) each strike refits QSA over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VrefRule {
    /// The hammer's kinetic energy plus the string's energy, as the piano voice does.
    IncomingAndString,
    /// The hammer's kinetic energy alone.
    Incoming,
}

/// A run: every frame, the initial energy `H^{−1/2}` (J) and, for QSA, each fit in force with
/// the sample it took over at.
#[derive(Debug, Clone)]
pub struct Record {
    /// One frame per sample.
    pub frames: Vec<Frame>,
    /// `H^{−1/2}` (J).
    pub initial_energy: f64,
    /// QSA's fits: (first sample, spline), in time order; empty for IMP and EXP.
    pub fits: Vec<(usize, QuadSpline)>,
}

/// A string struck again and again.
#[derive(Debug, Clone, PartialEq)]
pub struct Restrike {
    /// The string.
    pub string: StringParams,
    /// The felt's law.
    pub law: PowerLaw,
    /// Sample rate (Hz).
    pub sample_rate: u32,
    /// Hammer mass (kg).
    pub hammer_mass: f64,
    /// Striking position (fraction of the length).
    pub position: f64,
    /// The strikes: sample and hammer speed (m/s), in time order.
    pub strikes: Vec<(usize, f64)>,
    /// The damper, if it lands.
    pub damper: Option<Damper>,
    /// Samples to render.
    pub samples: usize,
    /// What each strike's QSA fit spans.
    pub v_ref: VrefRule,
}

impl Restrike {
    /// What a run listens to: the bridge force.
    pub const PICKUP: Pickup = Pickup::point(OutputKind::BridgeForce, 0.5);

    /// The prepared string (every mode below [`MAX_FREQUENCY`] and Nyquist).
    pub fn modal_string(&self) -> ModalString {
        let fs = f64::from(self.sample_rate);
        ModalString::band_limited(self.string, fs, MAX_FREQUENCY.min(0.5 * fs))
            .expect("the sweep's strings have valid parameters")
    }

    /// The largest compression the QSA fit of any strike spans (m): the fit of the strike with
    /// the most energy. Known only after a run, so this is the first strike's.
    pub fn y_ref(&self) -> f64 {
        let v = self.strikes.first().map_or(0.0, |&(_, v)| v);
        self.law.compression_at_energy((0.5 * self.hammer_mass * v * v).max(f64::MIN_POSITIVE))
    }

    /// Every frame and the initial energy of a run with `method` (QSA with `segments`).
    pub fn frames_and_energy(&self, method: Method, segments: usize) -> (Vec<Frame>, f64) {
        let record = self.run(method, segments);
        (record.frames, record.initial_energy)
    }

    /// A run with `method` (QSA with `segments`), with QSA's fits.
    pub fn run(&self, method: Method, segments: usize) -> Record {
        let string = self.modal_string();
        let params = HammerStringParams {
            string: self.string,
            hammer: HammerParams { mass: self.hammer_mass, velocity: 0.0, position: self.position, gap: 1.0 },
            pickup: Self::PICKUP,
        };
        let mut core = HammerCore::new(string, &params);
        let mut solvers = Solvers::new(self.law);
        let mut shares = Vec::new();
        damper_shares(core.string(), self.position, &mut shares);
        let (mut extra, mut damper_now, mut since_update) = (Vec::new(), 0.0, 0.0);
        let dt = 1.0 / f64::from(self.sample_rate);
        let initial = core.energy();
        let (mut work, mut next) = (0.0, 0);
        let mut frames = Vec::with_capacity(self.samples);
        // The fit QSA starts with, in force until a strike's fit replaces it.
        let mut fits = if method == Method::Qsa { vec![(0, solvers.qsa.spline().clone())] } else { Vec::new() };
        for n in 0..self.samples {
            while let Some(&(at, speed)) = self.strikes.get(next)
                && at <= n
            {
                next += 1;
                // The energy of the state before the strike, the contact's share included: a
                // hammer still pressing on the string is caught with its felt's compression.
                let before = frames.last().map_or(initial, |f: &Frame| f.energy);
                let string_energy = core.string().energy();
                // The felt starts two samples of travel beyond the string, as the voice throws it.
                let hammer = HammerParams {
                    mass: self.hammer_mass,
                    velocity: speed,
                    position: self.position,
                    gap: 2.0 * speed * dt,
                };
                core.strike(&hammer);
                // The new felt is clear of the string: no contact energy after the strike.
                work += core.energy() - before;
                let v_ref = match self.v_ref {
                    VrefRule::IncomingAndString => hammer.kinetic_energy() + string_energy,
                    VrefRule::Incoming => hammer.kinetic_energy(),
                };
                let y_ref = self.law.compression_at_energy(v_ref.max(f64::MIN_POSITIVE));
                // A fit that cannot be made keeps the previous solver, as the voice does.
                if solvers.restart(method, self.law, y_ref, segments, core.compressions()) && method == Method::Qsa {
                    fits.push((n, solvers.qsa.spline().clone()));
                }
            }
            if let Some(d) = self.damper.filter(|d| n >= d.at) {
                damper_now += (d.rate - damper_now) * (1.0 - (-dt / d.time).exp());
                since_update += dt;
                if since_update >= DAMPER_UPDATE {
                    since_update = 0.0;
                    let before = core.string().energy();
                    extra.clear();
                    extra.extend(shares.iter().map(|g| damper_now * g));
                    core.string_mut().set_extra_decay(&extra);
                    core.refresh_coupling();
                    work += core.string().energy() - before;
                }
            }
            let mut frame = match solvers.method {
                Method::Qsa => core.step::<_, true>(&mut solvers.qsa),
                Method::Imp => core.step::<_, true>(&mut solvers.imp),
                Method::Exp => core.step::<_, true>(&mut solvers.exp),
            };
            frame.control_work = work;
            frames.push(frame);
        }
        Record { frames, initial_energy: initial, fits }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsa_dsp::preset::piano_note;

    fn c4(strikes: Vec<(usize, f64)>, damper: Option<Damper>) -> Restrike {
        let note = piano_note(60);
        Restrike {
            string: note.string,
            law: PowerLaw::new(note.kappa, note.alpha).unwrap(),
            sample_rate: 48_000,
            hammer_mass: note.hammer_mass,
            position: note.strike_position,
            strikes,
            damper,
            samples: 9_600,
            v_ref: VrefRule::IncomingAndString,
        }
    }

    /// A pianissimo strike 50 ms after a fortissimo one, with the damper landing (500 1/s, felt
    /// settling in 2 ms) two samples into the second contact: the booked balance closes to
    /// rounding (1e-12 of the largest energy over 9,600 steps), and the booked work is the two
    /// hammers' kinetic energies less what the hammers carried away, plus the small jumps of the
    /// numerical energy at the rate changes.
    #[test]
    fn the_balance_closes_through_restrikes_and_a_damper_landing_in_contact() {
        for method in [Method::Qsa, Method::Imp, Method::Exp] {
            let strikes = vec![(0, 6.0), (2_400, 0.3)];
            let (free, _) = c4(strikes.clone(), None).frames_and_energy(method, 6);
            let touch = (2_400..free.len()).find(|&n| free[n].force < 0.0).expect("the second strike touches");
            let set = c4(strikes, Some(Damper { at: touch + 2, rate: 500.0, time: 0.002 }));
            let (frames, e0) = set.frames_and_energy(method, 6);
            assert!(frames[touch + 2].force < 0.0, "{method:?}: the damper lands in contact");
            let scale = frames.iter().fold(e0.abs(), |m, f| m.max(f.energy.abs()));
            let drift = frames.iter().map(|f| (f.balance() - e0).abs()).fold(0.0, f64::max) / scale;
            assert!(drift <= 1e-12, "{method:?}: drift {drift:e}");
            let thrown = 0.5 * set.hammer_mass * (6.0f64 * 6.0 + 0.3 * 0.3);
            let work = frames.last().unwrap().control_work;
            assert!(work < thrown && work > 0.3 * thrown, "{method:?}: work {work} J of {thrown} J thrown");
        }
    }
}
