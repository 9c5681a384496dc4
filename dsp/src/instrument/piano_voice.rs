//! A piano voice: a key's unison of strings on its bridge ([`UnisonCore`]), with its hammer,
//! damper and solvers, reused note after note. "The string" below is every string of the unison.
//!
//! # A note's life
//!
//! - **Strike.** The hammer is thrown at the string from just beyond where the string is under it
//!   ([`UnisonCore::strike`]): on a string at rest that is the usual small gap; on a string still
//!   swinging from an earlier strike (a repeated note), the felt meets it wherever it is, at the
//!   relative speed of the two, as a hammer flying free from the action does. The QSA fit spans
//!   the hammer's kinetic energy plus the string's energy and that of its motion on other
//!   voices' bridges: all the energy there is, so no compression the contact can reach lies
//!   beyond the fit's last knot.
//! - **Damper.** Note-off lets the damper down unless the sustain pedal holds it, on every key
//!   below [`FIRST_UNDAMPED_KEY`]: the top strings have none and ring on. A damper is a
//!   felt pad pressing along the string beside the strike point ([`DAMPER_WIDTH`] long): a
//!   distributed dashpot, whose share of mode `i` is the mean of `sin²(β_i x)` under the pad.
//!   Every mode decays at `σ_i + D·g_i`, with `g_i` that mean over mode 1's, so the damper takes
//!   the high modes (which the pad sees at every phase, `g_i → ½/sin²`) two to four times faster
//!   than the fundamental (a modelling choice: dashpot density uniform under the felt, modes
//!   uncoupled). A mode with a node under a rigid pad would hardly be damped; felt is compliant
//!   and touches the string beyond its nominal length, so no mode gets less than the fundamental
//!   (`g_i ≥ 1`). `D`, the damper's rate at the fundamental, moves towards the `Damper` setting
//!   with time constant `damper_time` as the felt settles (towards 0 as it lifts). The rates
//!   change the string's coefficients, never its state ([`ModalString::set_extra_decay`]), so the
//!   sound dies away continuously however fast the damper lands.
//! - **Half-pedalling.** With the sustain pedal part of the way down the dampers hover above the
//!   strings ([`damper_lift`]). A hovering damper's target is the share of `D` that the strings'
//!   swing beyond its lift gives ([`contact_share`]), measured under the pad's middle every
//!   [`HOVER_UPDATE`]; each partner's is judged by its own swing at the same fraction of its
//!   length. Every partner joins the bridge, as with the pedal down.
//! - **Partners.** The strings of the other keys whose modes meet the key's partials ring with
//!   it on its bridge while their dampers are off (docs/physics.md §14, [`Dampers`]): all of them
//!   with the sustain pedal down; with it up, those of the keys held down and those without a
//!   damper. A key starts with those free at its strike; the others join once their dampers lift
//!   (the pedal goes down, or their keys), at the first block with the felt off the strings (a
//!   few keys a block, see [`PARTNER_SEEKS`](super::PARTNER_SEEKS)), at rest on the bridge's line
//!   ([`UnisonCore::add_partners`]), their dampers lifting as the pedal's do. Lifting the pedal,
//!   or letting their keys go, lets their dampers down; they stay on the bridge until the key's
//!   next strike from silence.
//! - **Strings ringing elsewhere.** A key's strings may already ring as a partner on other
//!   voices' bridges when it is struck. The hammer meets them where they are in all the copies
//!   (docs/physics.md §14.3): the instrument hands the voice their motion there at the striking
//!   point, at the strike ([`PianoVoice::meet`]) and at every step while the hammer can still
//!   touch ([`PianoVoice::render_shared`]), and renders those voices first.
//! - **Release.** A voice is free again once its strings are silent: their energy and its
//!   partners' (the hammer flying off and the bridge's slowest modes do not count) below
//!   [`RELEASE_ENERGY`] of its latest strike's, with the hammer flying away (a silent string cannot
//!   reach it). The partners count, since those without dampers ring on after the key's release.
//!   The energy here and in the guard (which counts the bridge too) is weighed with its own modal
//!   stiffnesses ([`ModalString::own_energy`]): the scheme's numerical energy depends on the decay
//!   rates, so a damper landing would make it jump although the string has not moved. It is
//!   weighed every control block, or every [`ENERGY_INTERVAL`] samples when the blocks are shorter.
//! - **Stealing.** With every voice busy, a new note takes the least audible voice, judged by the
//!   mean square of its output over its latest window of at least [`LOUDNESS_WINDOW`], closed at a
//!   control block's start so that it does not depend on how the host cuts its buffers
//!   ([`PianoVoice::loudness`]). A note struck since its voice's latest window closed has not been
//!   heard yet and counts as the loudest: the notes of a chord never take one another's voices
//!   while older notes sound, nor does a note struck just after another. The stolen voice
//!   fades at [`STEAL_RATE`] (a decay rate added to every mode, again without touching the state)
//!   for [`STEAL_TIME`], then its new note starts on a fresh string.
//! - **Shedding.** When the host's audio thread cannot keep up, the plugin has the least audible
//!   voices fade the same way with no note to follow ([`PianoVoice::shed`]): they fall silent and
//!   their notes end.
//! - **Guard.** With no source but the hammer, the string can never hold more than the energy of
//!   the latest strike. A string found with more than [`GUARD_FACTOR`] times that fades out over
//!   the control block and falls silent; a non-finite sample silences it at once (the samples
//!   rendered with it are zero). Both are counted ([`PianoVoice::guard_trips`]): a last line of
//!   defence that the tests check never fires.

use crate::bridge::{BridgeParams, SOUNDBOARD_CONDUCTANCE};
use crate::contact::{Method, PowerLaw};
use crate::exciter::HammerParams;
use crate::instrument::memo::{ENERGY_INTERVAL, Memo};
use crate::instrument::partners::PartnerTable;
use crate::instrument::settings::{HARDNESS_RANGE, Settings, hammer_speed};
use crate::instrument::solvers::Solvers;
use crate::preset::{piano_note, stretch_cents, strike_position};
use crate::scene::{MAX_PARTNERS, Shared, UnisonCore, UnisonParams, Watch};
use crate::string::{Damping, ModalString, StringParams};

/// Energy below which a voice that is not touching its hammer is released, relative to the
/// energy of its latest strike: 100 dB down. The dry output is then 96 to 126 dB below the
/// note's peak, from C1 to A6 with the pedal up and down: below a 16-bit floor for a note peaking
/// at full scale. A slide voice is judged the same way, its string's motion against its pluck.
pub const RELEASE_ENERGY: f64 = 1e-10;

/// How far a voice's energy may exceed its bound before the guard silences it: the strike's
/// energy for a piano voice, the energy at the pluck plus the controls' work for a slide voice.
pub const GUARD_FACTOR: f64 = 10.0;

/// A key struck again while it rings: the strings' energy (J) and the voicing gain before the
/// strike, and the gain of the strike's level ([`super::voicing_gain`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Restruck {
    energy: f64,
    voicing: f64,
    gain: f64,
}

impl Restruck {
    /// The one gain that serves the ringing and `added` joules more from the strike, their powers
    /// weighted by their energies: `√((E g² + ΔE g_new²) / (E + ΔE))`. A strike that takes energy
    /// from the strings (meeting them as they move away) adds none.
    fn voicing_with(&self, added: f64) -> f64 {
        let added = added.max(0.0);
        let total = self.energy + added;
        if total > 0.0 {
            ((self.energy * self.voicing * self.voicing + added * self.gain * self.gain) / total).sqrt()
        } else {
            self.gain
        }
    }
}

/// The guard's fade-out: a voice caught over its bound is faded linearly to silence across one
/// control block (no step in the output), then brought to rest at the next block.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GuardFade {
    /// While fading: the gain now and its decrease per sample (negative while turning back up).
    fade: Option<(f64, f64)>,
}

impl GuardFade {
    /// Start fading out over the next `samples` samples.
    pub fn start(&mut self, samples: usize) {
        // From the gain a fade turned back up had reached, not from full gain at once.
        let gain = self.fade.map_or(1.0, |(gain, _)| gain);
        self.fade = Some((gain, gain.max(f64::MIN_POSITIVE) / samples.max(1) as f64));
    }

    /// Turn a fade under way back up to full gain over `samples` samples, from the gain it has
    /// reached (no step in the output); nothing when not fading.
    pub fn resume(&mut self, samples: usize) {
        if let Some((gain, step)) = &mut self.fade {
            *step = -(1.0 - *gain) / samples.max(1) as f64;
        }
    }

    /// Forget the fade (the voice has been silenced).
    pub fn clear(&mut self) {
        self.fade = None;
    }

    /// Whether it is fading out.
    pub fn is_fading(&self) -> bool {
        self.fade.is_some_and(|(_, step)| step > 0.0)
    }

    /// Whether a fade has reached silence.
    pub fn is_silent(&self) -> bool {
        self.fade.is_some_and(|(gain, step)| step > 0.0 && gain <= 0.0)
    }

    /// Apply the fade to a rendered block (no change when not fading).
    pub fn apply(&mut self, out: &mut [f64]) {
        self.apply_together([out]);
    }

    /// Apply the fade to blocks rendered together, the same gain on each at each sample.
    pub fn apply_together<const N: usize>(&mut self, mut outs: [&mut [f64]; N]) {
        if let Some((gain, step)) = &mut self.fade {
            let len = outs.iter().map(|o| o.len()).min().unwrap_or(0);
            for i in 0..len {
                for out in outs.iter_mut() {
                    out[i] *= *gain;
                }
                *gain = (*gain - *step).clamp(0.0, 1.0);
            }
            if *step <= 0.0 && *gain >= 1.0 {
                self.fade = None;
            }
        }
    }
}

/// Decay rate that silences a stolen voice before its new note (1/s): −87 dB in 5 ms.
pub const STEAL_RATE: f64 = 2000.0;

/// How long a stolen voice fades before its new note starts (s).
pub const STEAL_TIME: f64 = 0.005;

/// The shortest window over which a voice's loudness is measured (s): longer than the hammer's
/// contact on every key (about 4 ms in the bass, Askenfelt & Jansson, JASA 88(1) 52–63, 1990; at
/// most 5.8 ms here, at C1: docs/physics.md §8.4), so that a note is heard past its strike before
/// it can be stolen, and than a period of the fundamental of every key from G♯1 (51.9 Hz) up, so
/// that a low note is not judged by where in its period a window falls.
pub const LOUDNESS_WINDOW: f64 = 0.020;

/// How loud a voice is, for stealing and shedding: the mean square of its output (bridge force,
/// N²) over its latest window of at least [`LOUDNESS_WINDOW`]. Windows close at control blocks'
/// starts, which are fixed in time, and a note is struck at its event's sample: the measure does
/// not depend on how the host cuts its buffers.
#[derive(Debug, Clone, Copy)]
struct Heard {
    /// Sum of the squared output since the window opened (N²).
    sum: f64,
    /// Samples since the window opened.
    samples: usize,
    /// Mean square over the latest closed window (N²); infinite while the note struck latest
    /// has not been heard over a whole window.
    loudness: f64,
}

impl Heard {
    const SILENT: Self = Self { sum: 0.0, samples: 0, loudness: 0.0 };

    /// A note is struck: it is not heard yet.
    fn struck(&mut self) {
        *self = Self { loudness: f64::INFINITY, ..Self::SILENT };
    }

    /// Add `out`'s squares to the window's sum one by one, so that the sum's rounding does not
    /// depend on where the host's buffers cut the window.
    fn add(&mut self, out: &[f64]) {
        self.sum = out.iter().fold(self.sum, |sum, x| sum + x * x);
        self.samples += out.len();
    }

    /// At a control block's start: close the window if it spans `window` samples.
    fn close(&mut self, window: usize) {
        if self.samples >= window {
            self.loudness = self.sum / self.samples as f64;
            self.sum = 0.0;
            self.samples = 0;
        }
    }
}

/// Length of a damper's felt pad along the string (m), from the strike point towards the bridge.
pub const DAMPER_WIDTH: f64 = 0.025;

/// The lowest key (MIDI) whose strings have no damper: E6, as on Steinway grands, whose dampers
/// end a semitone lower (docs/physics.md §6.5). A grand's shortest strings ring only a few
/// seconds, leave no room for a damper's head, and ring in sympathy with the keys below; makers
/// leave the top 18 to 21 keys undamped.
pub const FIRST_UNDAMPED_KEY: u8 = 88;

/// Whether MIDI key `key` has a damper (docs/physics.md §6.5).
pub fn has_damper(key: u8) -> bool {
    key < FIRST_UNDAMPED_KEY
}

/// The middle of the damper's pad on a string `length` (m) long struck at `position` (fraction
/// of the length): half of [`DAMPER_WIDTH`] from the striking point towards the bridge.
fn pad_at(position: f64, length: f64) -> f64 {
    (position + 0.5 * DAMPER_WIDTH / length).min(1.0)
}

/// Where the dampers are: how far the sustain pedal holds them above the strings, and the keys
/// whose dampers their keys or the sostenuto pedal hold clear of them, with those of the keys
/// without a damper (docs/physics.md §6.5).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Dampers {
    /// How far the sustain pedal holds the dampers above the strings at their pads (m): 0 with
    /// the pedal up (they rest on the strings), infinite with it down (clear of any motion), in
    /// between while it is partly down ([`damper_lift`]).
    pub lift: f64,
    /// The keys held down, one bit per MIDI key (bit `k` for key `k`).
    pub held: u128,
    /// The keys whose dampers the sostenuto pedal holds up (those held down as it went down).
    pub caught: u128,
}

impl Dampers {
    /// The keys from [`FIRST_UNDAMPED_KEY`] up, one bit per MIDI key.
    const UNDAMPED: u128 = u128::MAX << FIRST_UNDAMPED_KEY;

    /// The dampers with the sustain pedal down, the keys held and caught none.
    pub const PEDAL_DOWN: Self = Self { lift: f64::INFINITY, held: 0, caught: 0 };

    /// The keys whose strings no damper rests on, one bit per MIDI key: every key's while the
    /// sustain pedal holds the dampers up at all.
    pub fn lifted(&self) -> u128 {
        if self.lift > 0.0 { u128::MAX } else { self.clear() }
    }

    /// The keys whose dampers are clear of their strings whatever the sustain pedal does.
    fn clear(&self) -> u128 {
        self.held | self.caught | Self::UNDAMPED
    }

    /// Whether the sustain pedal holds the dampers partly up, where they touch a string only as
    /// far as it swings beyond their lift.
    pub fn hovering(&self) -> bool {
        self.lift > 0.0 && self.lift.is_finite()
    }

    /// The share of a damper's full rate that the sustain pedal leaves a damper to take from
    /// strings swinging `swing` (m) at its pad (read only while [`hovering`](Self::hovering)): 1
    /// resting on them, 0 with the pedal down, else [`contact_share`].
    pub fn share(&self, swing: impl FnOnce() -> f64) -> f64 {
        if self.lift == 0.0 {
            1.0
        } else if self.hovering() {
            contact_share(swing() / self.lift)
        } else {
            0.0
        }
    }
}

/// The share of a resting damper's rate that a damper held `g` above a string swinging with
/// amplitude `A` at its pad takes, from `reach = A/g` (docs/physics.md §6.5): the felt touches
/// the string only beyond `g`, on the arc `|θ − π/2| < φ` of each period of `u = A sin θ`, with
/// `cos φ = g/A`, and as a dashpot it takes there the share of the period's `∫ v² dt` that falls
/// on that arc, `(φ − sin φ cos φ)/π`: 0 while `A ≤ g`, rising to ½ as `g/A → 0`, the felt then
/// touching every upswing (resting on the string, it also follows it down: 1).
pub fn contact_share(reach: f64) -> f64 {
    if !(reach > 1.0) {
        return 0.0;
    }
    let cos = (1.0 / reach).min(1.0);
    let phi = cos.acos();
    (phi - phi.sin() * cos) / std::f64::consts::PI
}

/// The dampers' lift (m) at the two ends of the sustain pedal's half-way zone.
pub const HOVER_LIFTS: (f64, f64) = (2e-6, 2e-3);

/// How far (m) the sustain pedal pressed `depth` of its travel (0..=1) holds the dampers above
/// the strings (docs/physics.md §6.5), with its half-way zone between
/// [`Settings::half_pedal_from`] and [`Settings::half_pedal_to`] (in either order): 0 (resting
/// on them) up to the zone's lower end, the pedal's lost motion; infinite (clear of any motion)
/// from its upper end; in between from [`HOVER_LIFTS`]`.0` to `.1` in equal ratios, so that
/// equal steps of the pedal move the level at which it holds a string by equal steps in dB.
/// With both ends at one point the pedal is a switch there: up to it resting, pressed on from
/// it clear, so that a switch at the full travel clears at the full travel and one at none
/// rests with the pedal up.
pub fn damper_lift(depth: f64, settings: &Settings) -> f64 {
    let (from, to) = (settings.half_pedal_from, settings.half_pedal_to);
    let (rest, clear) = (from.min(to), from.max(to));
    if depth >= clear && depth > 0.0 {
        f64::INFINITY
    } else if !(depth > rest) {
        0.0
    } else {
        let (low, high) = HOVER_LIFTS;
        low * (high / low).powf((depth - rest) / (clear - rest))
    }
}

/// Move a damper's decay rate `rate` (1/s) the fraction `step` of the way to `target`, landing on
/// it once within 0.1 % (of 1/s at least): the felt settling with its time constant.
fn settle(rate: &mut f64, target: f64, step: f64) {
    *rate += (target - *rate) * step;
    if (target - *rate).abs() <= 1e-3 * target.max(1.0) {
        *rate = target;
    }
}

/// The bit of MIDI key `key` in a [`Dampers`] mask.
fn bit(key: u8) -> u128 {
    1 << (key & 127)
}

/// Shortest interval between updates of the string's coefficients while a damper moves (s): the
/// rates change smoothly, so recomputing them every ~0.7 ms (32 samples at 44.1 kHz) is enough,
/// and at N_b = 1 it keeps a landing damper from costing a pass of exponentials every sample.
pub const DAMPER_UPDATE: f64 = 0.000_7;

/// Interval between measurements of the strings' swing at the damper's pad, and shortest
/// interval between updates of their coefficients, while the sustain pedal holds the dampers
/// partly up (s): a hovering damper's rate follows the swing as it decays, over tenths of a
/// second, and each update is a pass of exponentials over the modes.
pub const HOVER_UPDATE: f64 = 0.004;

/// A note to play: MIDI channel (0..16), key (0..128), velocity (0, 1], whether the soft pedal
/// shifts the hammer, and the note's CC74.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Strike {
    /// MIDI channel, 0..=15.
    pub channel: u8,
    /// MIDI key, 0..=127.
    pub key: u8,
    /// Note velocity in (0, 1].
    pub velocity: f64,
    /// The soft pedal (una corda) is down: the hammer misses one string of a bichord or
    /// trichord ([`struck_strings`]). The slide guitar ignores it.
    pub shifted: bool,
    /// The note's CC74 (its own brightness, else its channel's), 0..=1, if one was sent: it
    /// voices the piano hammer's felt ([`felt_hardness`]). The slide guitar reads its channel's
    /// when it is asked to.
    pub timbre: Option<f64>,
}

/// What a voice holds before its first note: C4 on channel 1, never struck.
const UNPLAYED: Strike = Strike { channel: 0, key: 60, velocity: 0.0, shifted: false, timbre: None };

/// CC74's middle, 64 of 0..=127: the felt as the `Hardness` setting has it.
pub const TIMBRE_CENTRE: f64 = 64.0 / 127.0;

/// How many times stiffer the felt is for every 32 steps of CC74 above its middle (softer below).
pub const TIMBRE_HARDNESS_STEP: f64 = 2.0;

/// The felt's stiffness relative to the per-note rule for a hammer set to `hardness` (the
/// setting) and voiced by the note's CC74 `timbre`: `hardness · 2^((127·timbre − 64)/32)`,
/// from a quarter at CC 0 to 3.9 times at 127, clamped to the setting's range (0.1–10), as a
/// technician hardens or softens a hammer by needling or ironing its felt. No CC74, or CC 64
/// (within a thousandth of a step, which a value passed as an `f32` fraction misses by 2.4·10⁻⁷),
/// leaves the setting exactly as it is.
pub fn felt_hardness(hardness: f64, timbre: Option<f64>) -> f64 {
    let Some(t) = timbre.filter(|t| t.is_finite()) else { return hardness };
    let steps = 127.0 * (t.clamp(0.0, 1.0) - TIMBRE_CENTRE);
    if steps.abs() < 1e-3 {
        return hardness;
    }
    (hardness * TIMBRE_HARDNESS_STEP.powf(steps / 32.0)).clamp(HARDNESS_RANGE.0, HARDNESS_RANGE.1)
}

/// How many strings of a unison of `strings` the hammer meets: one fewer when the una corda
/// shifts it (a grand's action moves sideways: a trichord is struck on two strings, a bichord on
/// one), all of them otherwise. A single string is still struck, on a softer part of the felt
/// that the model leaves out (docs/physics.md §12.9).
pub fn struck_strings(strings: usize, shifted: bool) -> usize {
    if shifted { strings.saturating_sub(1).max(1) } else { strings }
}

/// The damper's share of each mode relative to the fundamental, `g_i` (module docs), for a pad
/// [`DAMPER_WIDTH`] long from `position` (fraction of the length) towards the bridge, written
/// into `out` (one entry per mode of `string`; never allocates within `out`'s capacity).
pub fn damper_shares(string: &ModalString, position: f64, out: &mut Vec<f64>) {
    let length = string.params().length;
    let (a, b) = (position * length, (position * length + DAMPER_WIDTH).min(length));
    // Mean of sin²(βx) over [a, b].
    let mean = |beta: f64| 0.5 - ((2.0 * beta * b).sin() - (2.0 * beta * a).sin()) / (4.0 * beta * (b - a));
    let first = string.wavenumbers().first().map_or(1.0, |&beta| mean(beta));
    out.clear();
    out.extend(string.wavenumbers().iter().map(|&beta| (mean(beta) / first).max(1.0)));
}

/// Some of `key`'s partners in `table`, in the table's order (strongest first).
#[derive(Debug)]
struct PartnerList<'a> {
    /// `(string, modes)` of each partner.
    strings: [(&'a ModalString, usize); MAX_PARTNERS],
    /// The key of each partner.
    keys: [u8; MAX_PARTNERS],
    count: usize,
    /// Every partner the table has for `key`, chosen or not, one bit per MIDI key.
    all: u128,
}

impl<'a> PartnerList<'a> {
    /// `key`'s partners in `table` among `keys` (one bit per MIDI key).
    fn among(table: &'a PartnerTable, key: u8, keys: u128) -> Self {
        let mut picks = [(0, 0); MAX_PARTNERS];
        let count = table.pick(key, &mut picks);
        let mut list =
            Self { strings: [(table.string(0), 0); MAX_PARTNERS], keys: [0; MAX_PARTNERS], count: 0, all: 0 };
        for &(i, modes) in &picks[..count] {
            let partner = PartnerTable::key(i);
            list.all |= bit(partner);
            if keys & bit(partner) != 0 {
                list.strings[list.count] = (table.string(i), modes);
                list.keys[list.count] = partner;
                list.count += 1;
            }
        }
        list
    }
}

/// A key's strings as they move on other voices' bridges, at its striking point: what its hammer
/// meets besides its own strings (docs/physics.md §14.3).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Elsewhere {
    /// `(β^{n−1}, β^n)` (m).
    pub motion: (f64, f64),
    /// How far from rest it can reach (m).
    pub reach: f64,
    /// The energy of the strings and bridges that move it (J).
    pub energy: f64,
}

impl std::ops::Add for Elsewhere {
    type Output = Self;

    fn add(self, other: Self) -> Self {
        let motion = (self.motion.0 + other.motion.0, self.motion.1 + other.motion.1);
        Self { motion, reach: self.reach + other.reach, energy: self.energy + other.energy }
    }
}

/// One piano voice.
#[derive(Debug, Clone)]
pub struct PianoVoice {
    core: UnisonCore,
    solvers: Solvers,
    /// The note it plays (valid while sounding).
    pub strike: Strike,
    /// Whether it produces sound.
    pub sounding: bool,
    /// Whether its key is held down.
    pub key_down: bool,
    /// Sample index of its latest note-on (for stealing the oldest).
    pub started: u64,
    /// Output gain of the key at the dynamic level it was last struck at ([`super::voicing_gain`]).
    pub voicing: f64,
    /// Output gain now: moves to `voicing` after a re-strike at another level.
    pub voiced: f64,
    /// A re-strike whose hammer has not left yet: what it added is weighed once it has.
    restruck: Option<Restruck>,
    /// Left and right gains now ([`super::pan_gains`]): they move to the key's when the stereo
    /// width changes. `None` for a note not mixed yet, which starts where the mix pans its key.
    pub pan: Option<[f64; 2]>,
    /// The damper's decay rate at the fundamental now, `D` (1/s), moving towards its target.
    damper: f64,
    /// The extra decay at the fundamental the string's coefficients hold now (1/s).
    applied: f64,
    /// The key of each of the core's partners.
    partner_keys: [u8; MAX_PARTNERS],
    /// The partners the table gave at the strike that may still join once their dampers lift
    /// (one bit per MIDI key).
    partners_waiting: u128,
    /// Each partner's damper's decay rate now (1/s), moving towards 0 while its key's strings are
    /// free and towards the damper's rate while they are not, and the rate its coefficients hold.
    partner_dampers: [f64; MAX_PARTNERS],
    partner_applied: [f64; MAX_PARTNERS],
    /// Seconds since the partners' coefficients were last updated.
    partner_since: f64,
    /// The amplitudes (m) of the strings' and each partner's swing at their dampers' pads, as
    /// last measured for dampers the sustain pedal holds partly up, and the seconds since then.
    swing: f64,
    partner_swing: [f64; MAX_PARTNERS],
    swing_age: f64,
    /// The middle of each partner's damper pad (fraction of its string's length).
    partner_pads: [f64; MAX_PARTNERS],
    /// The damper's share of each mode relative to the fundamental, `g_i` (module docs).
    damper_shape: Vec<f64>,
    /// What `damper_shape` was made for: the first string, its modes, the striking point and
    /// the unison's modes.
    damper_for: Option<(StringParams, usize, f64, usize)>,
    /// Scratch: the extra decay rate of each mode (1/s).
    extra: Vec<f64>,
    /// Seconds since the coefficients were last updated.
    since_update: f64,
    /// The fraction of the way a damper's rate moves in a block, kept while the block's length and
    /// the damper's time stay.
    damper_step: Memo,
    /// Samples since the guard and the release last weighed the voice's energy.
    unweighed: usize,
    /// Energy of the latest strike (J), the reference for releasing the voice.
    reference_energy: f64,
    /// Striking position of the latest strike (fraction of the length).
    position: f64,
    /// What the next strike meets of the strings' motion on other voices' bridges
    /// ([`meet`](Self::meet)).
    meets: Elsewhere,
    /// Samples of steal fade left before `pending` starts, counted down as they are rendered.
    fade_left: usize,
    /// A note waiting for the fade to finish, and the settings of its own sample, which it is
    /// struck with wherever the block it starts in falls.
    pending: Option<Strike>,
    pending_settings: Settings,
    /// Whether the pending note's key was released while it waited.
    pending_released: bool,
    /// Whether the note (or the pending one) has a brightness of its own, which its channel's
    /// CC74 no longer overrides.
    own_brightness: bool,
    /// Fading out with no note to follow (shed to lighten the load).
    shedding: bool,
    /// How loud it has been lately.
    heard: Heard,
    /// The guard's fade-out, once the voice has been caught over its bound.
    guard_fade: GuardFade,
    /// How many times the guard has silenced this voice.
    trips: u32,
}

impl PianoVoice {
    /// A silent voice with room for `modes` modes, at `sample_rate` (Hz).
    pub fn new(modes: usize, sample_rate: f64) -> Self {
        let law = PowerLaw::new(1e9, 2.5).expect("a valid law");
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let mut core = UnisonCore::new(modes, &board, sample_rate).expect("the soundboard is a valid bridge");
        let note = piano_note(60);
        let unison = UnisonParams { string: note.string, strings: note.strings, detune: [0.0; 3] };
        core.retune(&unison, 20_000.0, note.strike_position).expect("the C4 rule is a valid string");
        let per_mode = || Vec::with_capacity(modes + crate::string::LANES);
        Self {
            damper_shape: per_mode(),
            damper_for: None,
            extra: per_mode(),
            core,
            solvers: Solvers::new(law),
            strike: UNPLAYED,
            sounding: false,
            key_down: false,
            started: 0,
            voicing: 1.0,
            voiced: 1.0,
            restruck: None,
            pan: None,
            damper: 0.0,
            applied: 0.0,
            partner_keys: [0; MAX_PARTNERS],
            partners_waiting: 0,
            partner_dampers: [0.0; MAX_PARTNERS],
            partner_applied: [0.0; MAX_PARTNERS],
            partner_since: 0.0,
            swing: 0.0,
            partner_swing: [0.0; MAX_PARTNERS],
            swing_age: f64::INFINITY,
            partner_pads: [0.0; MAX_PARTNERS],
            since_update: 0.0,
            damper_step: Memo::EMPTY,
            unweighed: 0,
            reference_energy: 0.0,
            position: note.strike_position,
            meets: Elsewhere::default(),
            fade_left: 0,
            pending: None,
            pending_settings: Settings::default(),
            pending_released: false,
            own_brightness: false,
            shedding: false,
            heard: Heard::SILENT,
            guard_fade: GuardFade::default(),
            trips: 0,
        }
    }

    /// The string a key gets under `settings`: the per-note rule with the relative settings, and
    /// tuned by the octave stretch (a lighter or heavier string: the pitch moves, B stays). A
    /// brighter or duller string, its bending stiffness scaled, is weighted so that its first
    /// partial stays where the rule puts it, `ρA` times `(1 + B')/(1 + B)`, as a tuner would tune
    /// it: brightness changes the timbre, not the tuning.
    pub fn string_for(key: u8, settings: &Settings) -> StringParams {
        let mut string = piano_note(key).string;
        let rule = string.inharmonicity();
        string.bending_stiffness *= settings.brightness;
        string.linear_density *= (1.0 + string.inharmonicity()) / (1.0 + rule);
        let ratio = 2f64.powf(settings.stretch * stretch_cents(key, settings.brightness) / 1200.0);
        string.linear_density /= ratio * ratio;
        string.damping = match string.damping {
            Damping::PerMode { b1, b3 } => Damping::PerMode { b1: b1 * settings.damping, b3: b3 * settings.damping },
            Damping::Viscous { eta0, eta2 } => {
                Damping::Viscous { eta0: eta0 * settings.damping, eta2: eta2 * settings.damping }
            }
        };
        string
    }

    /// Where the hammer strikes `key`'s strings under `settings` (fraction of the length).
    pub fn striking_point(key: u8, settings: &Settings) -> f64 {
        (strike_position(key) * settings.strike_position).clamp(0.02, 0.5)
    }

    /// Whether `key` struck now strikes this voice's sounding strings again (a voice the guard
    /// is fading meets the strike silent: see [`play_with`](Self::play_with)).
    fn restrikes(&self, key: u8) -> bool {
        self.sounding && self.strike.key == key && self.pending.is_none() && !self.guard_fade.is_fading()
    }

    /// Where this voice's hammer strikes `key` now (fraction of the length): on strings it sounds
    /// already, where it struck them, which is where their hammer meets them (the strings are
    /// tuned for a striking point as they are struck from rest); else where `settings` put it.
    pub fn striking_point_for(&self, key: u8, settings: &Settings) -> f64 {
        if self.restrikes(key) { self.position } else { Self::striking_point(key, settings) }
    }

    /// Play `strike` now: on the same string if this voice already sounds that key (a re-strike),
    /// else on a freshly tuned string at rest. Never allocates.
    pub fn play(&mut self, strike: Strike, settings: &Settings, now: u64) {
        self.play_with(strike, settings, now, None);
    }

    /// [`play`](Self::play), a key struck from silence ringing with those of its partners from
    /// the table `partners.0` whose strings are free of their dampers (`partners.1`;
    /// docs/physics.md §14).
    pub fn play_with(
        &mut self,
        strike: Strike,
        settings: &Settings,
        now: u64,
        partners: Option<(&PartnerTable, Dampers)>,
    ) {
        // A voice the guard is fading has left its bound: its note ends here, counted, and the
        // new strike (on its key too) meets strings at rest, as on any silent voice.
        if self.guard_fade.is_fading() {
            self.trip();
        }
        let note = piano_note(strike.key);
        let position = self.striking_point_for(strike.key, settings);
        let restrike = self.restrikes(strike.key);
        self.own_brightness = false;
        let gain = super::voicing_gain(strike.key, strike.velocity);
        let strings = note.strings as f64;
        if !restrike {
            self.restruck = None;
            self.voicing = gain;
            self.voiced = gain;
            self.pan = None;
            if !self.tune(strike.key, settings, position, partners) {
                return;
            }
        }
        let fs = self.core.string().sample_rate();
        let velocity = hammer_speed(strike.velocity);
        // The rule's hammer is one string's share (see `PianoNote`): the whole hammer weighs
        // `S` shares, and its felt is as stiff as the strings it meets.
        let met = struck_strings(note.strings, strike.shifted);
        self.core.set_struck(met);
        let mass = note.hammer_mass * settings.hammer_mass * strings;
        // The felt starts two samples of travel beyond the string, so the hammer lands almost at once.
        let hammer = HammerParams { mass, velocity, position, gap: 2.0 * velocity / fs };
        let string_energy = self.core.own_energy();
        if restrike {
            // The voicing is the gain a strike at its level is heard with: it belongs to what the
            // new strike adds, not to the sound already ringing, which keeps its own. One gain
            // serves both, their powers weighted by their energies (`Restruck`). What the strike
            // adds is known once its hammer has left; until then the voicing moves only down,
            // to the blend with the hammer's whole energy, so that a loud strike into a soft
            // note's ringing is not heard at the soft note's gain.
            self.settle_voicing();
            let before = Restruck { energy: string_energy, voicing: self.voicing, gain };
            self.voicing = self.voicing.min(before.voicing_with(hammer.kinetic_energy()));
            self.restruck = Some(before);
            // A key going down lifts its damper half-way through its travel, well before the
            // hammer arrives: a key struck again while its damper falls meets free strings.
            if self.applied != 0.0 {
                self.core.set_extra_decay(&[], 0.0);
            }
            self.damper = 0.0;
            self.applied = 0.0;
        }
        let elsewhere = std::mem::take(&mut self.meets);
        self.core.set_background(elsewhere.motion, elsewhere.reach);
        self.core.strike(&hammer);
        self.position = position;
        // All the energy there is: the hammer's and the string's (a re-strike meets a moving
        // string), and what the strings' motion elsewhere can bring: with `E` that motion's
        // energy, the key's copy holds at most `(√(E_hammer + E_string + E) + √E)²`, the copies'
        // sum and the motion elsewhere each bounded in the energy's norm.
        let carried = hammer.kinetic_energy() + string_energy + elsewhere.energy;
        self.reference_energy = (carried.sqrt() + elsewhere.energy.sqrt()).powi(2).max(f64::MIN_POSITIVE);
        if !self.fit_felt(&strike, settings) {
            return;
        }
        self.strike = strike;
        self.sounding = true;
        self.key_down = true;
        self.started = now;
        self.heard.struck();
    }

    /// Give the hammer `strike`'s felt under `settings` ([`felt_hardness`]) and fit the solvers
    /// to it over the strike's reference energy; whether the felt law was valid.
    fn fit_felt(&mut self, strike: &Strike, settings: &Settings) -> bool {
        let note = piano_note(strike.key);
        let met = struck_strings(note.strings, strike.shifted);
        let stiffness = note.kappa * felt_hardness(settings.hardness, strike.timbre) * met as f64;
        let Ok(law) = PowerLaw::new(stiffness, note.alpha) else { return false };
        let y_ref = law.compression_at_energy(self.reference_energy);
        self.solvers.restart(settings.method, law, y_ref, settings.segments, self.core.compressions())
    }

    /// Set the note's brightness, its own CC74 (0..=1), under `settings`. It voices the felt of a
    /// strike still to come: one waiting for a steal fade, or one struck at this very sample
    /// (`now`), whose hammer has not moved yet, as a host sends a note's expressions just after
    /// its note-on. A hammer already thrown keeps its felt. From then on the channel's CC74 no
    /// longer reaches the note ([`set_channel_timbre`](Self::set_channel_timbre)).
    pub fn set_brightness(&mut self, value: f64, settings: &Settings, now: u64) {
        if self.voice_felt(Some(value), settings, now) {
            self.own_brightness = true;
        }
    }

    /// The CC74 of the channels `channels` (one bit per MIDI channel) changed to `value` (0..=1,
    /// `None` for none): as [`set_brightness`](Self::set_brightness) for a strike still to come on
    /// one of them, unless the note has a brightness of its own, so that a CC74 sent at the
    /// note-on's sample counts whether it comes before the note-on or after it.
    pub fn set_channel_timbre(&mut self, channels: u16, value: Option<f64>, settings: &Settings, now: u64) {
        let note = self.pending.unwrap_or(self.strike);
        if channels >> (note.channel & 15) & 1 == 1 && !self.own_brightness {
            self.voice_felt(value, settings, now);
        }
    }

    /// Voice the felt of a strike still to come with the CC74 `value` (see
    /// [`set_brightness`](Self::set_brightness)); whether there was one. A voice fading out with
    /// no note to follow (shed or choked) has none, though it may have begun to fade at this
    /// sample.
    fn voice_felt(&mut self, value: Option<f64>, settings: &Settings, now: u64) -> bool {
        if let Some(pending) = &mut self.pending {
            pending.timbre = value;
            return true;
        }
        if !(self.sounding && !self.shedding && self.started == now) {
            return false;
        }
        let strike = Strike { timbre: value, ..self.strike };
        if self.fit_felt(&strike, settings) {
            self.strike = strike;
        }
        true
    }

    /// Tune the strings to `key` under `settings`, struck at `position` (fraction of the length),
    /// at rest, with those of its partners from the table `partners.0` whose strings are free of
    /// their dampers (`partners.1`), the dampers off; whether the unison was valid.
    fn tune(
        &mut self,
        key: u8,
        settings: &Settings,
        position: f64,
        partners: Option<(&PartnerTable, Dampers)>,
    ) -> bool {
        let note = piano_note(key);
        let fs = self.core.string().sample_rate();
        let unison = UnisonParams {
            string: Self::string_for(key, settings),
            strings: note.strings,
            detune: note.detune.map(|d| d * settings.unison_detune),
        };
        let max_frequency = settings.max_frequency.min(0.5 * fs);
        // The per-note rule and the clamped settings always give a valid unison.
        // Partners ring only while their dampers are off: all of them from a key struck with
        // the pedal down; with it up, those of the keys held down and those without a damper.
        // Under their dampers they would barely move, and cost as much. The others wait until
        // their dampers lift.
        let (retuned, list) = match partners {
            Some((table, dampers)) => {
                let list = PartnerList::among(table, key, dampers.lifted());
                let strings = &list.strings[..list.count];
                (self.core.retune_with_partners(&unison, max_frequency, position, strings), Some(list))
            }
            None => (self.core.retune(&unison, max_frequency, position), None),
        };
        if retuned.is_err() {
            return false;
        }
        self.partner_keys = list.as_ref().map_or([0; MAX_PARTNERS], |l| l.keys);
        if let Some(list) = &list {
            self.place_partner_pads(settings, list, 0, self.core.partners());
        }
        let present = self.partner_keys[..self.core.partners()].iter().fold(0, |m, &k| m | bit(k));
        self.partners_waiting = list.map_or(0, |l| l.all & !present);
        // The partners there start free.
        self.partner_dampers = [0.0; MAX_PARTNERS];
        self.partner_applied = [0.0; MAX_PARTNERS];
        self.shape_damper(position);
        self.damper = 0.0;
        self.applied = 0.0;
        self.swing_age = f64::INFINITY;
        // The new note's clocks start with it: when its dampers' coefficients are next updated
        // and when its energy is next weighed do not depend on the note the voice played before.
        self.since_update = 0.0;
        self.partner_since = 0.0;
        self.unweighed = 0;
        true
    }

    /// Tune this silent voice to `key` under `settings`, as a strike with the sustain pedal down
    /// would, with every partner `table` gives, and leave it silent. What that key's notes write
    /// of the voice's arrays is then in memory (a page the audio thread first writes costs it a
    /// fault), the table has searched the key's partners, and the voice is as fresh for any other
    /// key. Returns how far the key reaches into the arrays: `(modes on the bridge, modes off
    /// it, most modes of one string)`. Never allocates.
    pub fn prepare(&mut self, key: u8, settings: &Settings, table: &PartnerTable) -> (usize, usize, usize) {
        if self.sounding || self.fading() {
            return (0, 0, 0);
        }
        let position = Self::striking_point(key, settings);
        if !self.tune(key, settings, position, Some((table, Dampers::PEDAL_DOWN))) {
            return (0, 0, 0);
        }
        let (coupled, free) = self.core.parts();
        (coupled, free, self.core.modes())
    }

    /// The waiting partners whose dampers have lifted (`lifted`, one bit per MIDI key) join the
    /// bridge beside those there, at rest where their dampers held them, their dampers lifting
    /// from the damper's rate. Those the bridge has no room for stop waiting.
    fn seek_partners(&mut self, settings: &Settings, table: &PartnerTable, lifted: u128) {
        let list = PartnerList::among(table, self.strike.key, lifted & self.partners_waiting);
        let had = self.core.partners();
        let added = self.core.add_partners(&list.strings[..list.count]);
        self.partner_keys[had..had + added].copy_from_slice(&list.keys[..added]);
        self.place_partner_pads(settings, &list, had, added);
        // A retuned table may no longer pair them: they stop waiting too.
        self.partners_waiting &= !lifted & list.all;
        if added > 0 {
            self.swing_age = f64::INFINITY;
            self.partner_dampers[had..had + added].fill(settings.damper_rate);
            self.partner_applied[had..had + added].fill(settings.damper_rate);
            let mut rates = [None; MAX_PARTNERS];
            rates[had..had + added].fill(Some(settings.damper_rate));
            self.core.set_partner_decays(&rates);
        }
    }

    /// Where the dampers of the `count` partners from the `first`-th on, `list`'s first ones in
    /// turn, touch their strings: each at its own key's pad.
    fn place_partner_pads(&mut self, settings: &Settings, list: &PartnerList, first: usize, count: usize) {
        let pads = &mut self.partner_pads[first..first + count];
        for (pad, (&key, (string, _))) in pads.iter_mut().zip(list.keys.iter().zip(&list.strings)) {
            *pad = pad_at(Self::striking_point(key, settings), string.params().length);
        }
    }

    /// The damper's share of each mode for a pad from the striking point `position`.
    fn shape_damper(&mut self, position: f64) {
        let string = self.core.string();
        let made_for = Some((*string.params(), string.modes(), position, self.core.modes()));
        if self.damper_for == made_for {
            return;
        }
        self.damper_for = made_for;
        damper_shares(string, position, &mut self.damper_shape);
        // A detuned string of the unison may keep a mode more than the first: it gets the
        // highest share.
        let last = self.damper_shape.last().copied().unwrap_or(1.0);
        self.damper_shape.resize(self.core.modes(), last);
    }

    /// Weigh a re-strike's voicing by what its strikes added to the strings' energy.
    fn settle_voicing(&mut self) {
        if let Some(restruck) = self.restruck.take() {
            self.voicing = restruck.voicing_with(self.core.own_energy() - restruck.energy);
        }
    }

    /// Fade out over [`STEAL_TIME`], then play `strike` under `settings`, those of its own sample
    /// (a stolen voice): it starts at the first control block after the fade. A voice fading out
    /// already keeps its fade, which has been taking its modes down at [`STEAL_RATE`] since it
    /// began: begun again, a key struck faster than the fade lasts would put its note off at every
    /// strike, and never sound.
    pub fn steal(&mut self, strike: Strike, settings: &Settings, now: u64) {
        let (fading, sample_rate) = (self.fading(), self.core.string().sample_rate());
        self.pending = Some(strike);
        self.pending_settings = *settings;
        self.pending_released = false;
        self.own_brightness = false;
        self.shedding = false;
        self.started = now;
        if !fading {
            self.fade_out(sample_rate);
        }
    }

    /// Fade out over [`STEAL_TIME`] and fall silent, the note ending: a sounding voice given up to
    /// lighten the load. Whether it began to fade (not if silent or fading already).
    pub fn shed(&mut self, sample_rate: f64) -> bool {
        if !self.sounding || self.fading() {
            return false;
        }
        self.shedding = true;
        self.fade_out(sample_rate);
        true
    }

    /// Fade out over [`STEAL_TIME`] and fall silent whatever the dampers, the note ending: a host
    /// choked the note. A note waiting for a steal fade is dropped, the fade under way ending the
    /// voice instead.
    pub fn choke(&mut self, sample_rate: f64) {
        if self.pending.take().is_some() {
            self.shedding = true;
        } else {
            self.shed(sample_rate);
        }
    }

    /// Every mode decays at [`STEAL_RATE`] for [`STEAL_TIME`], the state untouched.
    fn fade_out(&mut self, sample_rate: f64) {
        self.fade_left = (STEAL_TIME * sample_rate).ceil() as usize;
        self.key_down = false;
        self.extra.clear();
        self.extra.resize(self.core.modes(), STEAL_RATE);
        self.core.set_extra_decay(&self.extra, STEAL_RATE);
        self.core.set_partner_decays(&[Some(STEAL_RATE); MAX_PARTNERS]);
        self.partner_applied = [f64::NAN; MAX_PARTNERS];
        self.applied = f64::NAN;
    }

    /// Whether the pending note starts at the coming block's start: its steal fade is over, or
    /// the guard's fade has silenced the old note already ([`begin_block`](Self::begin_block)).
    fn pending_starts_now(&self) -> bool {
        self.fade_left == 0 || self.guard_fade.is_fading()
    }

    /// The key of the pending note this voice starts at the coming block's start, and the
    /// settings it is struck with.
    pub fn starts_now(&self) -> Option<(u8, &Settings)> {
        self.pending.filter(|_| self.pending_starts_now()).map(|p| (p.key, &self.pending_settings))
    }

    /// The MIDI channel whose pedals reach this voice from the coming block's start: that of the
    /// pending note it starts then, else its note's.
    pub fn channel_now(&self) -> u8 {
        self.pending.filter(|_| self.pending_starts_now()).map_or(self.strike.channel, |p| p.channel)
    }

    /// The key this voice will sound once any steal fade is over.
    pub fn upcoming_key(&self) -> Option<u8> {
        match self.pending {
            Some(p) => Some(p.key),
            None => self.sounding.then_some(self.strike.key),
        }
    }

    /// Release `key` on `channel` if this voice plays it (or will, after a steal fade).
    pub fn key_up(&mut self, channel: u8, key: u8) {
        self.keys_up(|c, k| (c, k) == (channel, key));
    }

    /// Release the key this voice plays (or will, after a steal fade) if `released(channel, key)`.
    pub fn keys_up(&mut self, released: impl Fn(u8, u8) -> bool) {
        match self.pending {
            Some(p) if released(p.channel, p.key) => self.pending_released = true,
            _ if self.sounding && released(self.strike.channel, self.strike.key) => self.key_down = false,
            _ => {}
        }
    }

    /// Release whatever key this voice plays.
    pub fn release(&mut self) {
        self.key_down = false;
        self.pending_released = true;
    }

    /// How many of its strings the latest strike's hammer met ([`struck_strings`]).
    pub fn strings_struck(&self) -> usize {
        self.core.struck()
    }

    /// The strings' and bridge's energy over the latest strike's reference, all the energy the
    /// strike had to give (the guard's premise: at most 1).
    pub fn energy_share(&self) -> f64 {
        self.core.own_energy() / self.reference_energy
    }

    /// How many times the guard has silenced this voice.
    pub fn guard_trips(&self) -> u32 {
        self.trips
    }

    /// Silence the voice at once, counted as a guard trip.
    fn trip(&mut self) {
        self.trips += 1;
        self.silence();
    }

    /// [`trip`](Self::trip), a note waiting for the voice kept: it starts at the next block's
    /// start, from rest, its steal fade no longer needed.
    fn trip_keeping_pending(&mut self) {
        let waiting = self.pending.map(|strike| (strike, self.pending_released));
        self.trip();
        if let Some((strike, released)) = waiting {
            (self.pending, self.pending_released) = (Some(strike), released);
        }
    }

    /// Measure the strings' swing at their damper's pad and each partner's at its own.
    fn measure_swings(&mut self) {
        self.swing = self.pad_swing();
        for j in 0..self.core.partners() {
            self.partner_swing[j] = self.core.partner_swing_at(j, self.partner_pads[j]);
        }
        self.swing_age = 0.0;
    }

    /// The amplitude (m) of the strings' widest swing under the damper's pad now
    /// ([`UnisonCore::swing_at`]): what a damper the sustain pedal holds partly up meets.
    pub fn pad_swing(&self) -> f64 {
        self.core.swing_at(pad_at(self.position, self.core.string().params().length))
    }

    /// As made: silent, with no note played yet, so that the voices are chosen for the next
    /// notes and weigh their energy as on a new instrument.
    pub fn reset(&mut self) {
        self.silence();
        self.strike = UNPLAYED;
        self.started = 0;
    }

    /// Stop at once: the string at rest, no pending note, no guard fade under way.
    pub fn silence(&mut self) {
        self.guard_fade.clear();
        self.core.reset();
        self.sounding = false;
        self.key_down = false;
        self.restruck = None;
        self.pending = None;
        self.shedding = false;
        self.fade_left = 0;
        self.damper = 0.0;
        self.heard = Heard::SILENT;
    }

    /// Whether the hammer touches the string (or is about to) in a sounding voice.
    pub fn in_contact(&self) -> bool {
        self.sounding && self.core.in_contact()
    }

    /// Whether this voice is being faded out, to make room for another note or shed.
    pub fn fading(&self) -> bool {
        self.pending.is_some() || self.shedding
    }

    /// The vibration the voice holds: its strings' and bridge's energy (J), the hammer left out.
    pub fn vibration(&self) -> f64 {
        self.core.own_energy()
    }

    /// Energy of the string and hammer (J).
    pub fn energy(&self) -> f64 {
        self.core.energy()
    }

    /// How loud the voice is now, what stealing and shedding rank voices by: the mean square of
    /// its output (bridge force, N²) over its latest window (at least `LOUDNESS_WINDOW`) times the
    /// square of its voicing gain, the share of it that reaches the output (the voicing evens the
    /// keys' loudness, up to 20 dB apart in bridge force); infinite for a note struck since that
    /// window closed, not heard yet.
    pub fn loudness(&self) -> f64 {
        self.heard.loudness * self.voicing * self.voicing
    }

    /// Work at a control-block boundary: start a pending note, bring in the partners whose
    /// dampers have lifted since the strike (`dampers`: the pedal went down, or their keys; while
    /// `seeks`, the voices that may still do so in this block, is above 0; it counts down), move
    /// the dampers towards their targets for the coming `len` samples, release the voice once
    /// silent.
    pub fn begin_block(
        &mut self,
        settings: &Settings,
        dampers: Dampers,
        len: usize,
        now: u64,
        mut partners: Option<&mut PartnerTable>,
        seeks: &mut usize,
    ) {
        if !self.sounding && !self.fading() {
            return;
        }
        if self.guard_fade.is_fading() {
            // The guard's fade has silenced the old note; a note waiting for the voice starts on
            // it now, from rest, its steal fade no longer needed.
            self.trip_keeping_pending();
            if self.pending.is_none() {
                return;
            }
        }
        if !self.sounding {
            // A silent voice renders nothing, so counts no fade down: it has nothing to fade.
            self.fade_left = 0;
        }
        let fs = self.core.string().sample_rate();
        self.heard.close((LOUDNESS_WINDOW * fs).ceil() as usize);
        if self.shedding && self.fade_left == 0 {
            self.silence();
            return;
        }
        if let Some(strike) = self.pending
            && self.fade_left == 0
        {
            self.pending = None;
            self.shedding = false;
            self.sounding = false;
            // The partner strings are tuned as the note's own strings are, for its settings, and
            // the table goes back to the block's for the voices after it.
            let own = self.pending_settings;
            let table = partners.as_deref_mut().map(|table| {
                table.request(&own);
                (table.ready(), dampers)
            });
            self.play_with(strike, &own, now, table);
            if let Some(table) = partners.as_deref_mut() {
                table.request(settings);
            }
            self.key_down = !self.pending_released;
        }
        if self.fading() {
            return;
        }
        if self.restruck.is_some() && self.core.hammer_leaving() {
            self.settle_voicing();
        }
        // Not while the felt may touch: the contact's coefficients would change under the solver.
        let lifted = dampers.lifted();
        if lifted & self.partners_waiting != 0
            && *seeks > 0
            && !self.core.in_contact()
            && let Some(table) = partners
        {
            *seeks -= 1;
            self.seek_partners(settings, table.ready(), lifted);
        }
        let span = len as f64 / fs;
        // The fraction of the way a damper's rate moves to its target over this block.
        let step = self.damper_step.get(-span / settings.damper_time, |x| 1.0 - x.exp());
        // A damper the pedal holds partly up takes what the strings' swing beyond it gives.
        if dampers.hovering() && self.swing_age >= HOVER_UPDATE {
            self.measure_swings();
        }
        self.swing_age += span;
        let update = if dampers.hovering() { HOVER_UPDATE } else { DAMPER_UPDATE };
        // The key may be held on another channel than the one that struck it last.
        let up = (dampers.caught | dampers.held) & bit(self.strike.key) != 0;
        let damped = !(self.key_down || up) && has_damper(self.strike.key);
        let target = if damped { settings.damper_rate * dampers.share(|| self.swing) } else { 0.0 };
        settle(&mut self.damper, target, step);
        self.since_update += span;
        if self.damper != self.applied && (self.since_update >= update || self.damper == target) {
            self.since_update = 0.0;
            self.applied = self.damper;
            self.extra.clear();
            self.extra.extend(self.damper_shape.iter().map(|g| self.damper * g));
            self.core.set_extra_decay(&self.extra, 0.0);
        }
        // The other keys' dampers fall on their strings as their keys are let go with the pedal
        // up, or the pedal lifts, and rise as the keys or the pedal go down, as the voice's own.
        let mut rates = [None; MAX_PARTNERS];
        let mut settled = true;
        let clear = dampers.clear();
        for j in 0..self.core.partners() {
            let swing = self.partner_swing[j];
            let free = clear & bit(self.partner_keys[j]) != 0;
            let target = if free { 0.0 } else { settings.damper_rate * dampers.share(|| swing) };
            let rate = &mut self.partner_dampers[j];
            settle(rate, target, step);
            if *rate != self.partner_applied[j] {
                rates[j] = Some(*rate);
                settled &= *rate == target;
            }
        }
        self.partner_since += span;
        if rates.iter().any(Option::is_some) && (self.partner_since >= update || settled) {
            self.partner_since = 0.0;
            self.partner_applied = self.partner_dampers;
            self.core.set_partner_decays(&rates);
        }
        // The energies take passes over the modes: every block, or every `ENERGY_INTERVAL`
        // samples when the blocks are shorter.
        self.unweighed += len;
        if self.unweighed < ENERGY_INTERVAL {
            return;
        }
        self.unweighed = 0;
        // What rings: the strings and the partners (those without dampers ring on after the key's
        // own strings fall silent, and feed them); the guard adds the bridge.
        let (ringing, bridge) = self.core.weigh();
        // The guard: with no source but the hammer, the string never holds more than the strike's
        // energy (the hammer's and what the string had); far more, or a non-finite state, is a
        // fault to silence, not to play.
        if !(ringing + bridge <= GUARD_FACTOR * self.reference_energy) {
            self.guard_fade.start(len);
        }
        // A silent unison cannot reach a hammer flying away from it.
        let silent = ringing < RELEASE_ENERGY * self.reference_energy;
        if self.core.hammer_leaving() && silent {
            self.sounding = false;
        }
    }

    /// The first string of the unison, for monitoring.
    pub fn string(&self) -> &ModalString {
        self.core.string()
    }

    /// `(compression (m), latest contact force (N), strike position (fraction of the length))`.
    pub fn contact(&self) -> (f64, f64, f64) {
        let (y, f) = self.core.contact();
        (y, f, self.position)
    }

    /// The strings' motion on other voices' bridges that the next strike of this voice meets
    /// at its striking point, with how far it can reach and the energy that moves it: the sum of
    /// [`partner_motion`](Self::partner_motion) over the voices that ring the key. Cleared by
    /// the strike.
    pub fn meet(&mut self, elsewhere: Elsewhere) {
        self.meets = elsewhere;
    }

    /// Whether the hammer can still touch the strings of a sounding voice (not retired).
    pub fn hammer_live(&self) -> bool {
        self.sounding && self.pending.is_none() && !self.core.retired()
    }

    /// The motion of the strings on other voices' bridges that the hammer last met, `β^n` (m).
    pub fn background(&self) -> f64 {
        self.core.background()
    }

    /// Striking position of the latest strike (fraction of the length).
    pub fn striking_position(&self) -> f64 {
        self.position
    }

    /// The index of `key` among the partners on this voice's bridge, if it sounds them.
    pub fn partner_index(&self, key: u8) -> Option<usize> {
        if !self.sounding {
            return None;
        }
        self.partner_keys[..self.core.partners()].iter().position(|&k| k == key)
    }

    /// The keys of the partners on this voice's bridge, one bit per MIDI key (none when silent).
    pub fn partner_mask(&self) -> u128 {
        if !self.sounding {
            return 0;
        }
        self.partner_keys[..self.core.partners()].iter().fold(0, |m, &k| m | bit(k))
    }

    /// Partner `j` at its key's striking point `ell` (docs/physics.md §14.3): its displacement
    /// there, how far it can reach (its bound per `√(2H)` times the most energy the guard lets
    /// this voice's strings and bridge hold, [`GUARD_FACTOR`] times its strike's) and its energy
    /// with the bridge's.
    pub fn partner_motion(&self, j: usize, ell: f64) -> Elsewhere {
        let watch = Watch::new(j, ell, 0);
        let reach = self.core.partner_reach(&watch) * (2.0 * GUARD_FACTOR * self.reference_energy).sqrt();
        Elsewhere { motion: self.core.partner_motion(&watch), reach, energy: self.core.partner_energy(j) }
    }

    /// Render `out.len()` samples of bridge force (N).
    pub fn render(&mut self, out: &mut [f64]) {
        self.render_shared(out, Shared::default());
    }

    /// [`render`](Self::render), the hammer meeting the strings' motion on other voices'
    /// bridges and the watched partners' motion handed on ([`UnisonCore::process_shared`]).
    pub fn render_shared(&mut self, out: &mut [f64], shared: Shared) {
        let s = &mut self.solvers;
        match s.method {
            Method::Qsa => self.core.process_shared(&mut s.qsa, out, shared),
            Method::Imp => self.core.process_shared(&mut s.imp, out, shared),
            Method::Exp => self.core.process_shared(&mut s.exp, out, shared),
        }
        self.heard.add(out);
        self.fade_left = self.fade_left.saturating_sub(out.len());
        if !self.heard.sum.is_finite() {
            out.fill(0.0);
            self.trip_keeping_pending();
        } else {
            self.guard_fade.apply(out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preset::key_frequency;

    const FS: f64 = 48000.0;

    fn struck(blocks: usize) -> (PianoVoice, Settings) {
        let settings = Settings::default();
        let mut voice = PianoVoice::new(200, FS);
        voice.play(Strike { channel: 0, key: 60, velocity: 0.7, shifted: false, timbre: None }, &settings, 0);
        let mut out = [0.0; 64];
        for _ in 0..blocks {
            voice.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
            voice.render(&mut out);
        }
        (voice, settings)
    }

    /// A struck string holds at most the strike's energy (measured 0.50 of it after 50 blocks),
    /// far inside the guard's bound of [`GUARD_FACTOR`] times it.
    #[test]
    fn a_struck_voice_stays_inside_its_energy_bound() {
        let (voice, _) = struck(50);
        let ratio = voice.core.own_energy() / voice.reference_energy;
        println!("string energy / strike energy: {ratio}");
        assert!(ratio <= 1.0);
        assert_eq!(voice.guard_trips(), 0);
    }

    /// A string holding more than [`GUARD_FACTOR`] times its strike's energy (here: a reference
    /// made a million times too small) fades out linearly over the next block, then the voice is
    /// silent with its string at rest, and the trip is counted.
    #[test]
    fn the_guard_fades_a_piano_voice_over_its_bound_within_one_block() {
        let (mut voice, settings) = struck(20);
        let mut twin = voice.clone();
        let (mut plain, mut faded) = ([0.0; 64], [0.0; 64]);
        twin.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
        twin.render(&mut plain);
        voice.reference_energy *= 1e-6;
        voice.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
        voice.render(&mut faded);
        for (i, (f, p)) in faded.iter().zip(&plain).enumerate() {
            assert_eq!(*f, p * (1.0 - i as f64 / 64.0), "sample {i}");
        }
        voice.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
        assert!(!voice.sounding);
        assert_eq!(voice.guard_trips(), 1);
        assert_eq!(voice.core.own_energy(), 0.0);
    }

    /// A voice silenced (all sound off) while the guard fades it plays its next note in full: the
    /// fade and the trip it leads to were the old note's.
    #[test]
    fn a_voice_silenced_during_a_guard_fade_plays_its_next_note() {
        let (mut voice, settings) = struck(20);
        voice.reference_energy *= 1e-6;
        let mut out = [0.0; 64];
        voice.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
        voice.render(&mut out);
        voice.silence();
        let mut fresh = PianoVoice::new(200, FS);
        let (mut heard, mut expected) = ([0.0; 64], [0.0; 64]);
        for (v, out) in [(&mut voice, &mut heard), (&mut fresh, &mut expected)] {
            v.play(Strike { channel: 0, key: 60, velocity: 0.7, shifted: false, timbre: None }, &settings, 0);
            for _ in 0..4 {
                v.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
                v.render(out);
            }
        }
        assert!(voice.sounding, "the new note sounds");
        assert_eq!(voice.guard_trips(), 0);
        assert_eq!(heard, expected, "as on a fresh voice");
    }

    /// A key struck on a voice the guard is fading, its own key again or another, sounds in full
    /// as on a fresh voice: the old note's trip is counted and the strike meets strings at rest.
    #[test]
    fn a_strike_during_a_guard_fade_sounds_as_on_a_fresh_voice() {
        for key in [60, 62] {
            let (mut voice, settings) = struck(20);
            voice.reference_energy *= 1e-6;
            let mut out = [0.0; 64];
            voice.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
            voice.render(&mut out);
            let mut fresh = PianoVoice::new(200, FS);
            let (mut heard, mut expected) = ([0.0; 256], [0.0; 256]);
            for (v, out) in [(&mut voice, &mut heard), (&mut fresh, &mut expected)] {
                v.play(Strike { channel: 0, key, velocity: 0.7, shifted: false, timbre: None }, &settings, 0);
                for block in out.chunks_mut(64) {
                    v.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
                    v.render(block);
                }
            }
            assert!(voice.sounding, "key {key}: the new note sounds");
            assert_eq!(voice.guard_trips(), 1, "key {key}");
            assert_eq!(heard, expected, "key {key}: as on a fresh voice");
        }
    }

    /// A stolen note starts at the first control block after its fade, wherever in a block the
    /// steal falls: stolen one sample into a block of 256 at 48 kHz (its fade 240 samples), it
    /// starts at the next block, 255 samples on, not one block later.
    #[test]
    fn a_stolen_note_starts_at_the_first_block_after_its_fade() {
        let (mut voice, settings) = struck(20);
        let mut out = [0.0; 256];
        voice.begin_block(&settings, Dampers::default(), 256, 0, None, &mut 0);
        voice.render(&mut out[..1]);
        let strike = Strike { channel: 0, key: 62, velocity: 0.7, shifted: false, timbre: None };
        voice.steal(strike, &settings, 1);
        voice.render(&mut out[1..]);
        voice.begin_block(&settings, Dampers::default(), 256, 256, None, &mut 0);
        assert!(voice.pending.is_none() && voice.strike.key == 62, "started at the block after the fade");
    }

    /// A stolen note is struck with the settings of its own sample, not those of the block it
    /// starts in: stolen under a soft felt (hardness 0.3), it sounds as a steal under that felt
    /// whose block also has it, though its block has the hardest (3.0).
    #[test]
    fn a_stolen_note_keeps_the_settings_of_its_own_sample() {
        let strike = Strike { channel: 0, key: 62, velocity: 0.7, shifted: false, timbre: None };
        let soft = Settings { hardness: 0.3, ..Settings::default() };
        let play = |block: &Settings| {
            let (mut voice, settings) = struck(20);
            voice.steal(strike, &soft, 0);
            let mut out = vec![0.0; 1024];
            for (k, chunk) in out.chunks_mut(64).enumerate() {
                voice.begin_block(if k == 0 { &settings } else { block }, Dampers::default(), 64, 0, None, &mut 0);
                voice.render(chunk);
            }
            out
        };
        let (own, hardest) = (play(&soft), play(&Settings { hardness: 3.0, ..soft }));
        assert!(own == hardest, "the note's own felt");
    }

    /// A note waiting for a voice whose state turns non-finite during its steal fade still
    /// sounds: the old note's trip is counted, and the new one starts at the next block.
    #[test]
    fn a_note_waiting_on_a_voice_that_turns_non_finite_still_sounds() {
        let (mut voice, settings) = struck(20);
        let strike = Strike { channel: 0, key: 62, velocity: 0.7, shifted: false, timbre: None };
        voice.steal(strike, &settings, 0);
        voice.core.fill_state(f64::NAN);
        let mut out = [0.0; 64];
        voice.render(&mut out);
        assert!(out.iter().all(|&x| x == 0.0) && voice.guard_trips() == 1);
        voice.begin_block(&settings, Dampers::default(), 64, 64, None, &mut 0);
        voice.render(&mut out);
        assert!(voice.sounding && voice.strike.key == 62, "the waiting note sounds");
        assert!(out.iter().all(|x| x.is_finite()) && out.iter().any(|&x| x != 0.0));
    }

    /// The loudness window spans a period of every key's fundamental from G♯1 up.
    #[test]
    fn the_loudness_window_spans_a_period_from_g_sharp_1_up() {
        assert!(LOUDNESS_WINDOW * key_frequency(32) >= 1.0 && LOUDNESS_WINDOW * key_frequency(31) < 1.0);
    }

    /// A note that steals a voice the guard is fading, held or let go while it waits, sounds in
    /// full at the next block as on a fresh voice: the old note's trip is counted, and the fade
    /// the guard began has silenced the voice already. It starts at that block for the
    /// instrument too: its key is the one it starts (which the instrument meets with the motion
    /// elsewhere) and its channel's pedals reach it.
    #[test]
    fn a_note_stealing_a_voice_during_a_guard_fade_sounds_as_on_a_fresh_voice() {
        for released in [false, true] {
            let (mut voice, settings) = struck(20);
            voice.reference_energy *= 1e-6;
            let mut out = [0.0; 64];
            voice.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
            voice.render(&mut out);
            let strike = Strike { channel: 3, key: 62, velocity: 0.7, shifted: false, timbre: None };
            voice.steal(strike, &settings, 0);
            if released {
                voice.key_up(3, 62);
            }
            let starts = voice.starts_now().map(|(key, _)| key);
            assert_eq!((starts, voice.channel_now()), (Some(62), 3), "released {released}");
            let mut fresh = PianoVoice::new(200, FS);
            fresh.play(strike, &settings, 0);
            if released {
                fresh.key_up(3, 62);
            }
            let (mut heard, mut expected) = ([0.0; 256], [0.0; 256]);
            for (v, out) in [(&mut voice, &mut heard), (&mut fresh, &mut expected)] {
                for block in out.chunks_mut(64) {
                    v.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
                    v.render(block);
                }
            }
            assert!(voice.sounding, "released {released}: the new note sounds");
            assert_eq!(voice.guard_trips(), 1, "released {released}");
            assert_eq!(voice.key_down, !released, "released {released}");
            assert_eq!(heard, expected, "released {released}: as on a fresh voice");
        }
    }

    /// How loud a voice is does not depend on how its control blocks are cut into render calls:
    /// C4 rendered in whole blocks of 64 samples and in calls of 1, 7 and 56 samples has the same
    /// loudness to the bit at every block, with the same samples.
    #[test]
    fn a_voices_loudness_does_not_depend_on_how_its_blocks_are_cut() {
        let (mut whole, settings) = struck(0);
        let mut cut = whole.clone();
        let (mut a, mut b) = ([0.0; 64], [0.0; 64]);
        for block in 0..40 {
            for v in [&mut whole, &mut cut] {
                v.begin_block(&settings, Dampers::default(), 64, 0, None, &mut 0);
            }
            whole.render(&mut a);
            let (first, rest) = b.split_at_mut(1);
            let (second, third) = rest.split_at_mut(7);
            for piece in [first, second, third] {
                cut.render(piece);
            }
            assert_eq!(a, b, "block {block}");
            assert_eq!(whole.loudness().to_bits(), cut.loudness().to_bits(), "block {block}");
        }
        assert!(whole.loudness().is_finite() && whole.loudness() > 0.0);
    }

    /// `voice`'s output for `key` struck at velocity 0.7, held for 20 blocks of 64 samples and let
    /// go for 20 more (the damper landing on the strings).
    fn played(voice: &mut PianoVoice, key: u8, settings: &Settings) -> Vec<f64> {
        voice.play(Strike { channel: 0, key, velocity: 0.7, shifted: false, timbre: None }, settings, 0);
        let (mut all, mut out) = (Vec::new(), [0.0; 64]);
        for block in 0..40 {
            if block == 20 {
                voice.key_up(0, key);
            }
            voice.begin_block(settings, Dampers::default(), 64, 0, None, &mut 0);
            voice.render(&mut out);
            all.extend_from_slice(&out);
        }
        all
    }

    /// A voice keeps the damper's shares of the modes between notes while the string and the
    /// striking point stay: one voice playing C4, C2, C4, then C4 struck nearer the agraffe (each
    /// once the one before was silenced) sounds each note, damper and all, as a fresh voice does,
    /// bit for bit.
    #[test]
    fn a_voice_damps_each_key_it_plays_as_a_fresh_voice_does() {
        let nearer = Settings { strike_position: 0.8, ..Settings::default() };
        let notes = [(60, Settings::default()), (36, Settings::default()), (60, Settings::default()), (60, nearer)];
        let mut voice = PianoVoice::new(400, FS);
        for (key, settings) in notes {
            // Free, as a voice whose note has ended.
            voice.silence();
            let heard = played(&mut voice, key, &settings);
            let fresh = played(&mut PianoVoice::new(400, FS), key, &settings);
            assert!(fresh.iter().any(|&x| x != 0.0));
            assert!(heard == fresh, "key {key} at striking point ×{}", settings.strike_position);
        }
    }

    /// Each partner's damper meets the partner's strings under its own key's pad, half the pad's
    /// width from that key's striking point, not at the struck key's fraction of the length: C4
    /// struck with the pedal up (the keys without dampers join at the strike), then ringing under
    /// a half-pressed pedal while the others join.
    #[test]
    fn a_partners_damper_meets_its_strings_under_its_own_keys_pad() {
        let settings = Settings::default();
        let mut table = PartnerTable::new(FS, &settings);
        let mut voice = PianoVoice::new(1000, FS);
        let strike = Strike { channel: 0, key: 60, velocity: 0.7, shifted: false, timbre: None };
        voice.play_with(strike, &settings, 0, Some((table.ready(), Dampers::default())));
        let at_strike = voice.core.partners();
        let half = Dampers { lift: damper_lift(0.5, &settings), ..Dampers::default() };
        let mut out = [0.0; 64];
        for _ in 0..100 {
            voice.begin_block(&settings, half, 64, 0, Some(&mut table), &mut 1);
            voice.render(&mut out);
        }
        let partners = voice.core.partners();
        assert!(at_strike > 0 && partners > at_strike, "{at_strike} partners at the strike, {partners} after");
        voice.measure_swings();
        let own = pad_at(voice.position, voice.core.string().params().length);
        let mut widest_apart: f64 = 0.0;
        for j in 0..partners {
            let key = voice.partner_keys[j];
            let length =
                table.string(usize::from(key - crate::instrument::partners::PARTNER_KEYS.start)).params().length;
            let pad = voice.partner_pads[j];
            let beyond = (pad - PianoVoice::striking_point(key, &settings)) * length;
            assert!((beyond - 0.5 * DAMPER_WIDTH).abs() < 1e-12, "partner {j} (key {key}): pad {beyond} m on");
            assert!(voice.partner_swing[j] == voice.core.partner_swing_at(j, pad));
            widest_apart = widest_apart.max((pad - own).abs());
        }
        assert!(widest_apart > 0.01, "the partners' pads lie within {widest_apart} of the key's own");
    }

    /// Preparing a silent voice for another key changes nothing it plays after: C4 struck with
    /// the pedal down, its partners ringing, sounds bit for bit as on a fresh voice once the voice
    /// was prepared for A0, for C8 or for C4 itself, and each preparation leaves the voice silent
    /// with A0 reaching further into one string's arrays than C4.
    #[test]
    fn a_prepared_voice_plays_as_a_fresh_voice_does() {
        let settings = Settings::default();
        let mut table = PartnerTable::new(FS, &settings);
        let pedal = Dampers::PEDAL_DOWN;
        let play = |voice: &mut PianoVoice, table: &mut PartnerTable| {
            voice.play_with(
                Strike { channel: 0, key: 60, velocity: 0.7, shifted: false, timbre: None },
                &settings,
                0,
                Some((table.ready(), pedal)),
            );
            let (mut all, mut out) = (Vec::new(), [0.0; 64]);
            for _ in 0..40 {
                voice.begin_block(&settings, pedal, 64, 0, Some(&mut *table), &mut 0);
                voice.render(&mut out);
                all.extend_from_slice(&out);
            }
            (all, voice.core.partners())
        };
        let (fresh, partners) = play(&mut PianoVoice::new(1000, FS), &mut table);
        assert!(partners > 0 && fresh.iter().any(|&x| x != 0.0));
        let mut reach = [0; 128];
        for key in [21, 108, 60] {
            let mut voice = PianoVoice::new(1000, FS);
            let (coupled, free, string) = voice.prepare(key, &settings, &table);
            assert!(coupled > 0, "key {key}: {coupled} modes on the bridge, {free} off it");
            assert!(!voice.sounding && voice.energy() == 0.0, "key {key} left the voice sounding");
            reach[usize::from(key)] = string;
            assert!(play(&mut voice, &mut table) == (fresh.clone(), partners), "prepared for key {key}");
        }
        assert!(reach[21] > reach[60], "A0 {} modes, C4 {}", reach[21], reach[60]);
    }

    /// With the octave stretch at 1 every octave outside the temperament octave is beatless on
    /// its lower key's second partial (to rounding), the temperament octave stays in equal
    /// temperament, and a stretch of 0 leaves every key there; at brightness 2 the stretch grows
    /// with B.
    #[test]
    fn stretched_octaves_are_beatless_on_the_lower_keys_second_partial() {
        let partial = |key: u8, n: usize, s: &Settings| PianoVoice::string_for(key, s).partial(n);
        for brightness in [0.0, 0.5, 1.0, 2.0, 4.0] {
            let stretched = Settings { brightness, ..Settings::default() };
            for key in 21..=108u8 {
                let f1 = partial(key, 1, &stretched);
                if key > 69 {
                    let below = partial(key - 12, 2, &stretched);
                    assert!((f1 / below - 1.0).abs() < 1e-12, "key {key} at {brightness}: {f1} Hz against {below} Hz");
                } else if key < 58 {
                    let (above, second) = (partial(key + 12, 1, &stretched), partial(key, 2, &stretched));
                    assert!(
                        (second / above - 1.0).abs() < 1e-12,
                        "key {key} at {brightness}: {second} against {above}"
                    );
                } else {
                    assert!((f1 / key_frequency(key) - 1.0).abs() < 1e-12, "key {key} at {brightness}: temperament");
                }
                let equal = Settings { stretch: 0.0, ..stretched };
                let f1 = partial(key, 1, &equal);
                assert!((f1 / key_frequency(key) - 1.0).abs() < 1e-12, "key {key} at {brightness} unstretched");
            }
        }
        let stretched = Settings::default();
        let cents = |key: u8, s: &Settings| 1200.0 * (partial(key, 1, s) / key_frequency(key)).log2();
        let brighter = Settings { brightness: 2.0, ..stretched };
        println!(
            "C8 {:.1} ct, C1 {:.2} ct; brightness 2: C8 {:.1} ct",
            cents(108, &stretched),
            cents(24, &stretched),
            cents(108, &brighter)
        );
        assert!(cents(108, &brighter) > 1.9 * cents(108, &stretched));
    }

    /// A non-finite state silences the voice in the same call: zeros, not NaN, and a trip.
    #[test]
    fn a_non_finite_piano_state_is_silenced_at_once() {
        let (mut voice, _) = struck(20);
        voice.core.fill_state(f64::NAN);
        let mut out = [1.0; 64];
        voice.render(&mut out);
        assert!(out.iter().all(|&x| x == 0.0));
        assert!(!voice.sounding);
        assert_eq!(voice.guard_trips(), 1);
    }

    /// [`contact_share`] against its definition: the share of `∫ v² dt` over a period of
    /// `u = A sin θ` that falls where `u > g`, summed over a million points of the period, to
    /// 1e-5 (the sum's error); 0 up to `A = g`, and ½ as `g/A → 0`.
    #[test]
    fn a_hovering_damper_takes_the_share_of_the_swings_motion_beyond_its_lift() {
        let n = 1_000_000;
        for reach in [1.0, 1.01, 1.2, 2.0, 5.0, 100.0] {
            let (mut beyond, mut all) = (0.0, 0.0);
            for k in 0..n {
                let theta = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
                let v2 = theta.cos().powi(2);
                all += v2;
                if reach * theta.sin() > 1.0 {
                    beyond += v2;
                }
            }
            let share = contact_share(reach);
            println!("A/g = {reach}: {share:.6} against {:.6}", beyond / all);
            assert!((share - beyond / all).abs() < 1e-5, "A/g = {reach}: {share} against {}", beyond / all);
        }
        assert_eq!(contact_share(0.5), 0.0);
        assert_eq!(contact_share(f64::NAN), 0.0);
        assert!((contact_share(1e9) - 0.5).abs() < 1e-9);
    }
}
