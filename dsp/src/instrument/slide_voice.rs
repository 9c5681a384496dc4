//! A slide-guitar voice: one string, its slide and hand, and the two fingers.
//!
//! The string is the slide-guitar preset (open A2, [`crate::preset::slide_guitar`]); the pitch
//! comes from where the slide stops it. Per control block the voice sets the scene's controls,
//! which the scene moves linearly across the block. The blocks are the instrument's, fixed in
//! time; a voice plucked from silence inside one begins its first block at once, for the rest of
//! it, so that the note sounds from its own sample. A note from silence finds the slide at rest
//! where the note puts it, whatever the voice played before: pressed onto the string as the
//! note's hand height presses it, in the scheme's static equilibrium of string, slide, hand,
//! resting finger and body, so that the pluck alone sounds (a player's slide is on the string
//! before the finger plucks), or held still above it where the hand height holds it off the
//! string; a hand height from a controller is read as the voice first renders, so that pressure
//! sent with the note-on counts:
//! - slide position `x_o` for `p` semitones above the open string ([`SlideScale`]: the ideal
//!   string's `L(1 − 2^(−p/12))`, less the end correction of the model's string): the
//!   `slide_position` setting, followed as it comes (host automation is already a gesture), or,
//!   when following keys, the played key's distance from the open string, glided towards with time
//!   constant `glide_time`; plus pitch bend × bend range, glided as well (a note from silence
//!   takes the bend its channel has at once); plus the note's own
//!   tuning (a host's per-note tuning expression, in semitones, followed as it comes). A hand
//!   moves a slide at a few metres per second at most and cannot change its speed at once, so
//!   the slide never travels faster than [`SLIDE_SPEED`] nor speeds up or slows down faster than
//!   [`SLIDE_ACCELERATION`] ([`Motion::approach`]: a jump of the setting or the tuning becomes a
//!   fast slide, a glide whose time jumps from block to block a smooth one); it is kept between
//!   5 mm and 0.8 L;
//! - hand height from the setting or a controller (0 lifts the slide by 2 mm, full presses it
//!   2 mm in: [`HAND_RANGE`]), moving at most [`HAND_SPEED`] and speeding up or slowing down at
//!   most [`HAND_ACCELERATION`] (the same law): the hand's damping `r_H` passes a change of its
//!   speed straight on to a pressed slide and so to the string, and a hand that reversed at once
//!   (the setting or a controller jumping at every control block) would kick the string with a
//!   step of force each time, heard as clicks. Lowering the slide, the hand sets it down gently
//!   ([`hand_reach`]: at most [`LANDING_ACCELERATION`], slowing to [`LANDING_SPEED`] before the
//!   slide touches and pressing on at that pace). The hand's spring is pulled along that plan
//!   averaged over the last block ([`HandPath`]), half a block behind it, its speed ramping within
//!   each block rather than stepping at block boundaries, where the hand's damping would pass the
//!   step on to a pressed slide;
//! - per note, a host's polyphonic modulation offsets the `slide_position` and `hand_height`
//!   settings (where they act: not following keys, and the hand height from the parameter), the
//!   sums clamped to the settings' ranges. Tuning, offsets and poly pressure belong to the note:
//!   every note-on starts them at 0. A voice that has not rendered since it was plucked from
//!   silence takes a new tuning or slide offset at once (a host sends a note's modulation right
//!   after its note-on); later they move the slide at its speed limit;
//! - the left finger trails the slide by 2 cm, damping the dead part of the string, resting on it
//!   with 0.3 N while the hand holds the slide on the string, its window clear of the nut and of
//!   the slide (it lifts where the dead part is too short: [`trailing_finger`]); with the slide
//!   lifted there is no dead part, and the finger lifts off the open string too: it lifts once the
//!   hand's plan rises [`FINGER_LIFT`] above the string's line and lands again once the plan is
//!   back at or below the line (a hand skimming the string, its plan overshooting the line a little
//!   as it turns, keeps its finger down; a note from silence finds it down unless its hand is
//!   higher than that). It lands and lifts over [`MUTE_TIME`] on a raised cosine, as the muting
//!   finger lands: a force stepping on or off would push the string aside at once;
//! - note-on plucks with the right finger at the plucking position: the force ramps up over
//!   [`PLUCK_TIME`] to [`pluck_force`] `0.3 + 2.7·velocity` N and falls to none over
//!   [`PLUCK_RELEASE`], at those times whatever the rate and the block (a block is cut at a
//!   corner of the force inside it, the pieces blocks of the core's of their own); note-off lays
//!   the finger on, its force rising to 0.3 N over [`MUTE_TIME`], muting the string (its damping
//!   at least [`MUTE_FINGER_DAMPING`]), and the hand stills the slide as the finger lands
//!   (damping it at least [`MUTE_HAND_DAMPING`]). The finger follows the `pluck_position`
//!   setting at the slide's speed limits, as it may be pressing, and plucks between the slide
//!   and the bridge: at the setting's place or halfway from the slide to the bridge, whichever
//!   is nearer the bridge ([`pluck_point`]);
//! - switching `follow_key` under a sounding note leaves the slide where it is, which then
//!   glides to where the new choice puts it.
//!
//! The slide's mass, the hand's stiffness and damping, the contact law (κ, α), the solver and
//! its segments belong to the voice's note: a note on a silent voice takes the current ones, and
//! a voice plucked again while it sounds keeps its own, solver state and all. Changed under a
//! pressed slide they would re-weigh the energy it holds: a stiffer contact or hand spring stores
//! more at the same compression or stretch, a heavier slide more at the same speed, and a solver
//! taking over from EXP (whose auxiliary variable, not the compression, carries the potential)
//! evaluates the potential at a compression EXP may have let grow far beyond it; energy from
//! nowhere, up to thousands of joules. So a silent voice whose note asks for other ones starts
//! from rest under them, pressed or lifted as any note from silence.
//!
//! # Guard
//!
//! The scheme's energy balance bounds the voice's energy by its energy at the pluck plus the work
//! its controls have done since. A voice whose state turns non-finite, or whose energy exceeds
//! [`GUARD_FACTOR`] times that bound, is faded out within the control block and brought to rest,
//! and counted ([`SlideVoice::guard_trips`]): a last line of defence that the tests and sweeps
//! check never fires. The energy is weighed every control block, or every [`ENERGY_INTERVAL`]
//! samples when the blocks are shorter.
//!
//! # Shedding
//!
//! When the host's audio thread cannot keep up, the plugin has the voices whose strings move
//! least fall silent ([`SlideVoice::shed`]): the output fades linearly over
//! [`STEAL_TIME`], then the string comes to rest with the slide lifted, and the note ends. A note
//! that takes a voice being shed (or choked) turns its output back up over the same time, from
//! where the fade had got to: its string still moves.

use crate::body::BodyParams;
use crate::contact::{Method, PowerLaw};
use crate::control::{Bow, Live};
use crate::exciter::SlideParams;
use crate::instrument::memo::{ENERGY_INTERVAL, Memo};
use crate::instrument::notes::NoteParam;
use crate::instrument::piano_voice::{GUARD_FACTOR, GuardFade, RELEASE_ENERGY, STEAL_TIME, Strike};
use crate::instrument::settings::{HAND_HEIGHT_LIMIT, HAND_RANGE, HandSource, Settings, SlideBody};
use crate::instrument::slide_scale::SlideScale;
use crate::instrument::solvers::Solvers;
use crate::preset::slide_guitar;
use crate::scene::{OutputKind, PIECE_TURN, Pickup, SlideControls, SlideCore, SlideStringParams};
use crate::string::ModalString;

/// Length of string the slide guitar's pickup senses (m): a single coil's, about an inch
/// (Tillman, "Response effects of guitar pickup position and width"). Modes whose half-wavelength
/// is shorter are averaged out (docs/physics.md §13.4).
pub const PICKUP_APERTURE: f64 = 0.0254;

/// MIDI key of the open string (A2).
pub const OPEN_KEY: u8 = 45;

/// How long a pluck pushes before the finger lets go (s).
pub const PLUCK_TIME: f64 = 0.008;

/// How long the string takes to slip off the plucking fingertip (s), the pluck's force falling
/// linearly to none: an estimate, as long as the control block of 64 samples at 44.1 kHz that
/// the instrument was voiced with. The release shapes the pluck's spectrum (a linear fall of
/// length `τ` weighs partial `f` by `sinc(f·τ)`), so it is a time, not a number of samples.
pub const PLUCK_RELEASE: f64 = 64.0 / 44_100.0;

/// Force of a finger resting on the string: trailing the slide, or muting after note-off (N).
pub const REST_FORCE: f64 = 0.3;

/// How long a finger laid on the string to mute it takes to reach [`REST_FORCE`] (s), on a
/// raised-cosine: a fingertip's pad landing (an estimate). A force stepping on within a block
/// pushes the string aside at once, a thump under the pickup however quiet the note has become.
pub const MUTE_TIME: f64 = 0.02;

/// The longest a muted string sounds (s): a voice still sounding this long after its finger
/// began to mute it is faded out as a shed one is, and its note ends. Muted, a note falls silent
/// with QSA and IMP whatever the settings (2.3 s after its note-off at the defaults, 4.7 s for the
/// heaviest slide on the softest hand without damping); EXP's pressed contact, stiff
/// beyond its stability (`κ` of 1e11 N/m^α and more at 22.05 kHz), can keep the string moving
/// for ever, inaudibly or as a drone.
pub const MUTED_LIMIT: f64 = 5.0;

/// The least damping (kg/s) of the hand holding the slide once its note is let go, reached as
/// the muting finger lands: the hand stills the slide as the finger mutes the string (the
/// default `Hand damping`). A slide on a hand without damping bobs on its spring for ever, and,
/// hitting the string or riding on it, keeps it sounding, so that the note never ends. Damping
/// only takes energy, so it may change under a sounding note.
pub const MUTE_HAND_DAMPING: f64 = 5.0;

/// The least damping (s/m) of the finger muting a note let go, reached as it lands (the default
/// `Finger damping`): a finger without damping only pushes the string aside, and the note would
/// ring on under it. Damping only takes energy, so it may change under a sounding note.
pub const MUTE_FINGER_DAMPING: f64 = 5.0;

/// How far the left finger trails the slide (m).
pub const TRAIL: f64 = 0.02;

/// Where the trailing finger rests behind the slide at `x_o` (m), its window `width` (m) wide,
/// and the share of its force it lays on the string: [`TRAIL`] behind the slide, its window kept
/// clear of the nut. Near the nut the dead part of the string is shorter than the window, so the
/// finger has nowhere to rest: its force falls to none as the dead part shrinks from one and a
/// half windows to one (the open string's key, with the slide 5 mm from the nut, has none).
pub fn trailing_finger(x_o: f64, width: f64) -> (f64, f64) {
    ((x_o - TRAIL).max(0.5 * width), ((x_o - width) / (0.5 * width)).clamp(0.0, 1.0))
}

/// How high above the string's line the hand's plan rises (m) before the trailing finger lifts
/// off the string: half the height a controller at 0 lifts the slide to ([`HAND_RANGE`]).
pub const FINGER_LIFT: f64 = 1e-3;

/// Fastest the slide travels along the string (m/s).
pub const SLIDE_SPEED: f64 = 5.0;

/// Largest acceleration of the slide along the string (m/s²): from rest to [`SLIDE_SPEED`] in
/// 50 ms, and an octave's shift (half the string) in 0.11 s, about as quick as a player's arm
/// (an estimate). A slide that changed its speed at once would start a kink along the string,
/// which the bridge passes on as a step (heard as a click on the acoustic guitar's body).
pub const SLIDE_ACCELERATION: f64 = 100.0;

/// Fastest the hand moves the slide towards or away from the string (m/s).
pub const HAND_SPEED: f64 = 0.5;

/// Largest acceleration of the hand (m/s²): from rest to [`HAND_SPEED`] in 10 ms, a quick
/// player's hand (5 g).
pub const HAND_ACCELERATION: f64 = 50.0;

/// Fastest the hand brings the slide down onto the string at rest, and presses it further in
/// (m/s): a player sets a slide down gently, and a slide landing at the hand's top speed claps
/// against the string (an estimate; the clap's level grows in proportion to the landing speed).
pub const LANDING_SPEED: f64 = 0.05;

/// How fast a player moves what the hand holds: the top speed (m/s) and the largest
/// acceleration (m/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// Top speed (m/s).
    pub speed: f64,
    /// Largest acceleration (m/s²).
    pub acceleration: f64,
}

/// The slide moved along the string; the plucking finger moves along it as fast.
pub const SLIDE_REACH: Reach = Reach { speed: SLIDE_SPEED, acceleration: SLIDE_ACCELERATION };

/// The hand pressing the slide onto the string or lifting it.
pub const HAND_REACH: Reach = Reach { speed: HAND_SPEED, acceleration: HAND_ACCELERATION };

/// Largest acceleration of the hand lowering the slide (m/s²): a quarter of
/// [`HAND_ACCELERATION`]. The slide rides on the hand's spring (about 90 Hz with the defaults),
/// and a hand whose acceleration jumps by `Δa` sets it swinging at up to `Δa/ω` (9 cm/s for
/// 50 m/s²), which it would bring onto the string on top of the hand's own speed.
pub const LANDING_ACCELERATION: f64 = HAND_ACCELERATION / 4.0;

/// How far above the string (m) the hand has slowed down to [`LANDING_SPEED`]: the slide lags
/// the hand on its spring, and the hand's plan changes its speed block by block.
pub const LANDING_MARGIN: f64 = 0.5e-3;

/// How much of its force a finger landing over [`MUTE_TIME`] on a raised cosine presses with,
/// `fraction` (0 to 1) of the way through its landing: `(1 − cos πx)/2`.
fn landed(fraction: f64) -> f64 {
    0.5 * (1.0 - (std::f64::consts::PI * fraction).cos())
}

/// Where the right finger plucks (m from the nut) on a string of `length` (m) with the slide at
/// `x_o` (m): at `pluck_position` of the length or halfway from the slide to the bridge,
/// whichever is nearer the bridge, so that the finger always plucks the part of the string that
/// sounds (a player's hand moves towards the bridge as the slide nears it).
pub fn pluck_point(pluck_position: f64, x_o: f64, length: f64) -> f64 {
    (pluck_position * length).max(0.5 * (x_o + length))
}

/// The reach of `hand` towards `target` (m) with the slide `gap` (m) above the string under it:
/// lowering the slide, the hand speeds up and slows down at most at `LANDING_ACCELERATION`
/// `a_l`, slowing down as the slide nears the string, `v ≤ √(v_land² + 2·a_l·(gap − margin))`
/// ([`LANDING_SPEED`], `LANDING_MARGIN`): the speed from which braking at `a_l` reaches `v_land`
/// at the margin, a bound whose slope stays within what the hand can follow at every control
/// block; it presses it further in at `v_land`; a hand too
/// fast to stop on its target at `a_l` (turned back from lifting)
/// brakes within `HAND_REACH`. Lifting, it moves within `HAND_REACH`.
pub fn hand_reach(hand: &Motion, target: f64, gap: f64) -> Reach {
    if target >= hand.position {
        return HAND_REACH;
    }
    let speed = (LANDING_SPEED * LANDING_SPEED + 2.0 * LANDING_ACCELERATION * (gap - LANDING_MARGIN).max(0.0)).sqrt();
    let speed = speed.min(HAND_SPEED);
    let too_fast = hand.velocity * hand.velocity > 2.0 * LANDING_ACCELERATION * (target - hand.position).abs();
    let acceleration = if too_fast { HAND_ACCELERATION } else { LANDING_ACCELERATION };
    Reach { speed, acceleration }
}

/// The share of the acceleration limit a `Motion` (the slide along the string, or the hand towards
/// it) brakes with towards a still target. Braking at the full limit, the block that meets the
/// target can change the speed by up to 9/8 of the limit (the bound on the speed from the distance
/// left is a block's worth optimistic); at 8/9 of it, that block stays within the limit too, and
/// arriving takes `v/(16a)` longer.
pub const BRAKING: f64 = 8.0 / 9.0;

/// What a [`Motion`] does with a target it would pass within a block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Passing {
    /// It stops on it, and sheds the speed it had over the next blocks, standing while the
    /// target stands: the hand (its path, [`HandPath`], smooths the stop) and the plucking
    /// finger, whose targets the player or the host sets.
    Never,
    /// It stops on it only where it can within its limits or where it was on the target as the
    /// block began (a target that stopped short or slowed);
    /// a target coming towards it, or one that jumps too close ahead to stop on, it passes and
    /// turns back to: the slide along the string, whose speed the string hears.
    Turning,
}

/// Something a player's hand moves, block by block: the slide along the string, or the hand
/// towards it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// Where it is at the end of the last block (m).
    pub position: f64,
    /// Its speed over the last block (m/s).
    pub velocity: f64,
    /// Where it was asked to be at the end of the last block (m).
    target: f64,
}

impl Motion {
    /// At rest at `position` (m), where it was asked to be.
    pub fn at_rest(position: f64) -> Self {
        Self { position, velocity: 0.0, target: position }
    }

    /// Move on by one control block of `span` seconds towards `target` (m), within `reach`,
    /// passing it as `passing` says. With `e` the distance to go, `Δv = a·span` the most the speed
    /// may change in a block and `u` the target's own speed over the block (at most the top
    /// speed; to a turning motion a step beyond it is a jump, after which the target stands
    /// where it landed):
    /// - where moving `e` in this block needs a speed `e/span` within the top speed, within `Δv`
    ///   of the present speed and within `Δv` of `u`, the motion meets the target: a target that
    ///   moves within the limits (a vibrato, a glide under way, automation drawn as a gesture)
    ///   is followed as it comes, and a still one is met slowly enough to stop on it in the next
    ///   block;
    /// - otherwise the speed changes by at most `Δv`, towards the fastest from which the motion
    ///   can still stop at a still target braking by `Δb` = [`BRAKING`]`·Δv` a block: slowing by
    ///   `Δb` a block from `v` covers `span·(v²/(2Δb) + v/2)`, so
    ///   `|v| ≤ (√(Δb² + 8Δb|e|/span) − Δb)/2`. A motion that would pass the target in this block
    ///   stops on it ([`Passing::Never`]), or ([`Passing::Turning`]) stops on it if it was on the
    ///   target as the block began or can stop there within `Δv`, its speed then the distance it
    ///   went: a target that stops short (the end of a ramp drawn as automation) is met where it
    ///   stops, never passed. A target coming towards a turning motion (a glide turning back, a
    ///   trill, a vibrato's turn that the motion lags), or one that jumps too close ahead of it
    ///   to stop on, is passed instead, and the motion turns back to it within its limits, as a
    ///   hand cannot stop at once.
    ///
    /// A turning motion's speed is the position's over the block, and it changes by at most `Δv`
    /// from block to block (jumps of the target and targets turning back included), except where
    /// a target it is on stops short or slows faster than that (a ramp drawn as automation that
    /// ends, or goes on more slowly): the motion then keeps on it; and, by a few
    /// percent, in the block where it catches up with a target that slows as it arrives (a
    /// glide's tail), since it brakes as for a still one. A motion that never passes keeps those
    /// bounds towards still targets and targets moving within the limits.
    pub fn approach(&mut self, target: f64, span: f64, reach: Reach, passing: Passing) {
        let (position, velocity) = (self.position, self.velocity);
        let previous = std::mem::replace(&mut self.target, target);
        if position == target && velocity == 0.0 {
            // At rest on the target: what the lines below give, without their divisions.
            return;
        }
        let error = target - position;
        let dv = reach.acceleration * span;
        let meeting = error / span;
        // The target's own speed. To a turning motion, a step it could not have made within the
        // reach (beyond its rounding) is a jump, after which it stands where it landed; one that
        // never passes meets a target that jumped only at its top speed.
        let step = target - previous;
        let jumped = passing == Passing::Turning && step.abs() > reach.speed * span * (1.0 + 1e-9);
        let own = if jumped { 0.0 } else { (step / span).clamp(-reach.speed, reach.speed) };
        if meeting.abs() <= reach.speed && (meeting - velocity).abs() <= dv && (meeting - own).abs() <= dv {
            (self.position, self.velocity) = (target, meeting);
            return;
        }
        let db = BRAKING * dv;
        let stopping = 0.5 * ((db * db + 8.0 * db * error.abs() / span).sqrt() - db);
        let wanted = error.signum() * reach.speed.min(stopping);
        self.velocity = velocity + (wanted - velocity).clamp(-dv, dv);
        let moved = self.velocity * span;
        let passes = moved.abs() >= error.abs() && moved * error >= 0.0;
        match passing {
            Passing::Never if passes => self.position = target,
            Passing::Never => self.position = position + moved,
            Passing::Turning => {
                // Where the target was as the block began, seen from the motion.
                let gap = if jumped { error } else { previous - position };
                let oncoming = own * gap < 0.0;
                let stops = gap == 0.0 || (meeting - velocity).abs() <= dv;
                if passes && stops && !oncoming {
                    (self.position, self.velocity) = (target, meeting);
                } else {
                    self.position = position + moved;
                }
            }
        }
    }

    /// Stop against the ends of `(lowest, highest)` (m), the range the targets lie in: a turning
    /// motion passing a target that turned back near an end would otherwise run on past it, past
    /// the nut, by up to `v²/(2a)`. Where it stops there, it stands still.
    pub fn stop_within(&mut self, (lowest, highest): (f64, f64)) {
        if !(lowest..=highest).contains(&self.position) {
            self.position = self.position.clamp(lowest, highest);
            self.velocity = 0.0;
        }
    }
}

/// The path the hand pulls the slide's spring along: the hand's [`Motion`], which moves linearly
/// within each control block and changes its speed at block boundaries, averaged over the last
/// block. With blocks of `T` seconds, the plan at `p_k` at their boundaries and moving at
/// `v_k = (p_{k+1} − p_k)/T` over block `k`, the average over the last `T` runs across block `k`
/// from the plan's midpoint `(p_{k−1} + p_k)/2` to `(p_k + p_{k+1})/2`, its speed ramping linearly
/// from `v_{k−1}` to `v_k`: a parabola whose speed never jumps, accelerating at
/// `(v_k − v_{k−1})/T` (within the plan's own limits), half a block behind the plan.
///
/// The slide rides on the hand's spring, and the hand's damping passes a step of the hand's speed
/// straight on to a pressed slide: a step of force at every block boundary, heard at multiples of
/// the block rate. An acceleration that steps only bends the force.
///
/// Where the blocks change length under a moving hand (a new `Control block`) the average
/// carried on ends off the new blocks' midpoints, by up to half the change in length times the
/// speed. The path keeps its place and takes the offset back as a [`Motion`] of its own within
/// the plan's reach (after one change of length its speed then steps by at most `a·T` at a block
/// boundary, as the plan's does; changes in quick succession can step it further), and is on
/// the midpoints again within about 11 ms at the hand's full reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandPath {
    /// Where the path is at the end of the last block (m).
    pub height: f64,
    /// The averaged plan's speed at the end of the last block: the plan's over that block (m/s).
    average_speed: f64,
    /// Where the plan was at the end of the last block (m).
    planned: f64,
    /// How far the path is off the averaged plan (m), taken back to none.
    offset: Motion,
    /// The offset's speed over the last block (m/s).
    offset_speed: f64,
}

impl HandPath {
    /// At rest at `height` (m), where the plan is.
    pub fn at_rest(height: f64) -> Self {
        Self { height, average_speed: 0.0, planned: height, offset: Motion::at_rest(0.0), offset_speed: 0.0 }
    }

    /// The path's speed at the end of the last block (m/s).
    #[cfg(test)]
    fn velocity(&self) -> f64 {
        self.average_speed + self.offset_speed
    }

    /// Move on by one block of `span` seconds, the plan reaching `planned` (m) at its end: the
    /// path across the block. The average, from `h_a` at speed `u` with the plan's speed `v` and
    /// midpoint `m` over the block, ends at `h_a + T(u + v)/2`, which is `m` while the blocks
    /// are equal; what it misses by goes to the offset, which then moves back towards none within
    /// `reach` (the plan's: near the string, the landing's limits). The path is the average's
    /// parabola, `(v − u)T/8` below the straight line between its ends halfway along, plus the
    /// offset's straight move.
    pub fn follow(&mut self, planned: f64, span: f64, reach: Reach) -> Bow {
        let speed = (planned - self.planned) / span;
        let middle = 0.5 * (self.planned + planned);
        // The path is the average plus its offset, so the offset with what the average misses
        // the midpoint by is where the path would end, less the midpoint.
        let taken = self.height + 0.5 * span * (self.average_speed + speed) - middle;
        self.offset.position = taken;
        self.offset.approach(0.0, span, reach, Passing::Never);
        let path = Bow {
            from: self.height,
            to: middle + self.offset.position,
            sag: (speed - self.average_speed) * span / 8.0,
        };
        self.offset_speed = (self.offset.position - taken) / span;
        (self.height, self.average_speed, self.planned) = (path.to, speed, planned);
        path
    }
}

/// The right finger's pluck force (N) for a note of `velocity` (0..1): `0.3 + 2.7·velocity`.
pub fn pluck_force(velocity: f64) -> f64 {
    0.3 + 2.7 * velocity
}

/// The pluck's corners at `sample_rate` (Hz), in samples from its start: where its force stops
/// rising ([`PLUCK_TIME`]) and where it has fallen to none ([`PLUCK_RELEASE`] later), each at
/// least a sample after the last.
fn pluck_corners(sample_rate: f64) -> [usize; 2] {
    let samples = |seconds: f64| ((seconds * sample_rate).round() as usize).max(1);
    let rise = samples(PLUCK_TIME);
    [rise, rise + samples(PLUCK_RELEASE)]
}

/// The share of its full force the plucking finger pushes with `n` samples into a pluck with
/// `corners` ([`pluck_corners`]): rising linearly to 1, then falling linearly to 0.
fn pluck_share(n: usize, [rise, end]: [usize; 2]) -> f64 {
    if n <= rise { n as f64 / rise as f64 } else { end.saturating_sub(n) as f64 / (end - rise) as f64 }
}

/// The rest of a control block that the pluck's corners cut: each corner inside a block begins a
/// block of the core's, so that the force, linear between corners, is the same function of time
/// at every rate and block length (at a block's end, a pluck let go up to a block late and over
/// a block moved its loudness by up to 1.6 dB across 44.1–192 kHz, and by 6 dB with blocks of
/// 256 samples).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Corners {
    /// The pieces still to begin, in order: each one's length (samples), the controls at its
    /// end and the sag of the hand's path across it (m).
    pieces: [Option<(usize, SlideControls, f64)>; 2],
    /// Samples left of the piece under way, while pieces are still to begin.
    left: usize,
}

impl Corners {
    /// A whole block.
    const NONE: Self = Self { pieces: [None; 2], left: 0 };

    /// Whether a piece is still to begin.
    fn pending(&self) -> bool {
        self.pieces.iter().any(Option::is_some)
    }

    /// The next piece to begin, taken off the list.
    fn take(&mut self) -> Option<(usize, SlideControls, f64)> {
        self.pieces.iter_mut().find_map(Option::take)
    }
}

/// What the voice reads from its MIDI channel.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChannelState {
    /// Pitch bend, −1..=1.
    pub bend: f64,
    /// Channel pressure, 0..=1.
    pub pressure: f64,
    /// Mod wheel, 0..=1.
    pub mod_wheel: f64,
    /// CC74 (MPE's third dimension), 0..=1, once one was sent.
    pub timbre: Option<f64>,
    /// Semitones of slide travel of a full bend, if the channel's pitch-bend sensitivity was set
    /// (RPN 0, or an MPE zone); else the `bend_range` setting.
    pub bend_range: Option<f64>,
    /// Semitones the channel's MPE zone's master channel bends every note of the zone.
    pub zone_bend: f64,
}

/// One slide voice.
#[derive(Debug, Clone)]
pub struct SlideVoice {
    core: SlideCore,
    solvers: Solvers,
    live: Live<SlideControls>,
    length: f64,
    /// The note it plays.
    pub strike: Strike,
    /// Whether it produces sound.
    pub sounding: bool,
    /// Whether its key is held down.
    pub key_down: bool,
    /// The channel's state at the latest note from silence: where its hand height came from,
    /// for the note's tuning and offsets that follow it before it renders.
    channel: ChannelState,
    /// On an MPE zone's member channel, the channel's state when the key was let go, which the
    /// released note keeps as it rings out: what the controller sends on the channel from then on
    /// is the next note's (its zone's master bend still reaches it).
    kept_channel: Option<ChannelState>,
    /// Sample index of its latest note-on.
    pub started: u64,
    /// Poly pressure of its key, 0..=1.
    pub poly_pressure: f64,
    /// The note's brightness, 0..=1, once the host sent one: it stands for its channel's CC74.
    pub brightness: Option<f64>,
    /// The note's tuning (semitones), added to the slide position.
    tuning: f64,
    /// The note's offset of the `slide_position` setting (semitones).
    slide_offset: f64,
    /// The note's offset of the `hand_height` setting (m).
    hand_offset: f64,
    /// Plucked from silence and not rendered since: per-note changes set the slide at once.
    fresh: bool,
    /// The part of the slide position that keys and bends ask for (semitones), after the glide.
    glided: f64,
    /// The slide along the string: its position `x_o` (m) from the nut, within [`SLIDE_REACH`].
    slide_motion: Motion,
    /// The hand's plan: its height (m), within [`HAND_REACH`], lowering within [`hand_reach`].
    /// The hand height `w_H` the core sees is `hand_path`'s.
    hand: Motion,
    /// The path the hand pulls the slide along, half a block behind `hand`.
    hand_path: HandPath,
    /// The plucking finger along the string (m), within [`SLIDE_REACH`]: it mutes where it
    /// plucks, and a finger pressing the string dragged along it in one block would thump.
    right: Motion,
    /// How long the finger has been muting the string (s): it lands over [`MUTE_TIME`].
    mute: f64,
    /// How far the trailing left finger has landed: 0 off the string, 1 resting on it with
    /// [`REST_FORCE`]; it moves by one in [`MUTE_TIME`] towards `trail_down`.
    trailing: f64,
    /// Whether the trailing finger is on its way onto the string (or resting on it).
    trail_down: bool,
    /// Whether the slide follows the played key (else the `slide_position` setting), as the
    /// voice last rendered.
    follow_key: bool,
    /// The slide and hand of the current note.
    slide: SlideParams,
    /// The contact law of the current note.
    law: PowerLaw,
    /// The solver settings of the current note: method and QSA segments.
    solver: (Method, usize),
    /// Energy at the latest pluck, string, slide and contact (J).
    energy_at_pluck: f64,
    /// The controls' work at the latest pluck (J).
    work_at_pluck: f64,
    /// The guard's fade-out, once the voice has been caught over its bound.
    guard_fade: GuardFade,
    /// The output's fade-out over [`STEAL_TIME`] once the voice is shed to lighten the load.
    shed_fade: GuardFade,
    /// How many times the guard has silenced this voice.
    trips: u32,
    /// Samples into the pluck at the end of the control block under way, while plucking.
    pluck: Option<usize>,
    /// The peak force of the pluck under way (N): its own note's, whatever legato notes glide
    /// to meanwhile without plucking.
    plucking_force: f64,
    /// The pieces of the control block under way that the pluck's corners cut.
    corners: Corners,
    /// Energy a pluck puts into the string (J): the release reference.
    reference_energy: f64,
    /// Recent peak of the string's kinetic energy (J), decaying with a 50 ms time constant.
    motion: f64,
    /// The latest block's exponentials and slide position, kept for the next block with the
    /// same arguments: at a control block of one sample they would be worked out every sample.
    glide_factor: Memo,
    motion_factor: Memo,
    position_at: Memo,
    /// Samples since the guard and the release last weighed the voice's energy.
    unweighed: usize,
    /// The guitar the current note sounds on: its string's end held and heard through the pickup,
    /// or on the acoustic body.
    pub body: SlideBody,
    /// Where the pickup's weights are made for (fraction of the length).
    pickup: f64,
    /// Where the slide stops this voice's string for each pitch.
    scale: SlideScale,
    /// Width of the trailing finger's window (m).
    left_width: f64,
}

impl SlideVoice {
    /// A silent voice at `sample_rate` (Hz).
    pub fn new(sample_rate: f64, settings: &Settings) -> Self {
        let g = slide_guitar();
        let string = ModalString::band_limited(g.string, sample_rate, settings.max_frequency.min(0.5 * sample_rate))
            .expect("the slide-guitar preset is a valid string");
        let length = g.string.length;
        let scale = SlideScale::new(&string);
        let rest = Self::at_rest((length, g.left.width), &scale, settings);
        let x_o = rest.slide_position;
        let slide = Self::slide_params(settings);
        let params = SlideStringParams {
            string: g.string,
            slide,
            left: g.left,
            right: g.right,
            block: settings.block,
            pickup: Pickup {
                kind: OutputKind::Velocity,
                position: settings.pickup_position,
                aperture: PICKUP_APERTURE,
            },
        };
        let law = PowerLaw::new(settings.slide_kappa, settings.slide_alpha).expect("clamped settings give a valid law");
        let mut core = SlideCore::new(string, &params, rest, rest);
        core.couple_statically();
        core.cut_blocks(PIECE_TURN);
        core.attach_body(&BodyParams::guitar(), false);
        Self {
            core,
            solvers: Solvers::new(law),
            live: Live(rest),
            length,
            strike: Strike { channel: 0, key: OPEN_KEY, velocity: 0.0, shifted: false, timbre: None },
            sounding: false,
            key_down: false,
            channel: ChannelState::default(),
            kept_channel: None,
            started: 0,
            poly_pressure: 0.0,
            brightness: None,
            tuning: 0.0,
            slide_offset: 0.0,
            hand_offset: 0.0,
            fresh: false,
            glided: 0.0,
            slide_motion: Motion::at_rest(x_o),
            hand: Motion::at_rest(HAND_RANGE.0),
            hand_path: HandPath::at_rest(HAND_RANGE.0),
            right: Motion::at_rest(rest.right_position),
            mute: 0.0,
            trailing: 0.0,
            trail_down: false,
            follow_key: settings.follow_key,
            slide,
            law,
            solver: (settings.method, settings.segments),
            energy_at_pluck: 0.0,
            work_at_pluck: 0.0,
            guard_fade: GuardFade::default(),
            shed_fade: GuardFade::default(),
            trips: 0,
            pluck: None,
            plucking_force: 0.0,
            corners: Corners::NONE,
            reference_energy: f64::MIN_POSITIVE,
            motion: 0.0,
            glide_factor: Memo::EMPTY,
            motion_factor: Memo::EMPTY,
            position_at: Memo::EMPTY,
            unweighed: 0,
            body: SlideBody::Pickup,
            pickup: settings.pickup_position,
            scale,
            left_width: g.left.width,
        }
    }

    /// The controls of a voice at rest on a string of length `length` (m), its trailing finger's
    /// window `left_width` (m) wide, under `settings`: the slide lifted above its position, the
    /// fingers off.
    fn at_rest((length, left_width): (f64, f64), scale: &SlideScale, settings: &Settings) -> SlideControls {
        let x_o = scale.position(settings.slide_position);
        SlideControls {
            slide_position: x_o,
            hand_height: HAND_RANGE.0,
            left_position: trailing_finger(x_o, left_width).0,
            left_force: 0.0,
            right_position: pluck_point(settings.pluck_position, x_o, length),
            right_force: 0.0,
        }
    }

    /// The slide and hand of `settings`.
    fn slide_params(settings: &Settings) -> SlideParams {
        SlideParams { mass: settings.slide_mass, stiffness: settings.hand_stiffness, damping: settings.hand_damping }
    }

    /// Pluck `strike` now. With `legato` (following keys, another key still held) the slide
    /// glides to the new key without a new pluck. A note from silence finds the slide where its
    /// key and `channel`'s bend put it: MPE controllers send a note's first bend before its
    /// note-on, and a channel keeps its bend from note to note.
    pub fn play(&mut self, strike: Strike, settings: &Settings, channel: &ChannelState, legato: bool, now: u64) {
        // A voice the guard is fading has left its bound: its note ends here, counted, and the
        // new one starts from silence (legato or not), as it would on any silent voice.
        if self.guard_fade.is_fading() {
            self.trip();
        }
        self.strike = strike;
        self.key_down = true;
        self.kept_channel = None;
        self.mute = 0.0;
        // A voice taken while it was being shed sounds again: its output turns back up over
        // `STEAL_TIME` from where the fade had got to, not in one step.
        let fs = self.core.string().sample_rate();
        self.shed_fade.resume((STEAL_TIME * fs).ceil() as usize);
        self.start_expression(0.0);
        if self.sounding {
            self.follow(settings);
        }
        if legato && self.sounding {
            return;
        }
        let from_silence = !self.sounding;
        if from_silence {
            // On the guitar of the moment: the string is moved onto (or off) the body as the
            // slide is lifted to where the note puts it, from rest.
            self.body = settings.slide_body;
            self.follow_key = settings.follow_key;
            self.glided = self.keys_and_bends(settings, channel);
            self.lift_to(self.scale.position(self.semitones(settings)), settings);
            self.fresh = true;
            self.channel = *channel;
            let Ok(law) = PowerLaw::new(settings.slide_kappa, settings.slide_alpha) else { return };
            let (slide, solver) = (Self::slide_params(settings), (settings.method, settings.segments));
            // The QSA fit spans twice the largest static push the hand and fingers can make: the
            // deepest hand press (the setting's, beyond a controller's) and the strongest pluck,
            // with the resting finger.
            let y_ref = slide.reference_compression(&law, HAND_HEIGHT_LIMIT, pluck_force(1.0), REST_FORCE);
            if !self.solvers.restart(solver.0, law, y_ref, solver.1, self.core.compressions()) {
                return;
            }
            (self.law, self.slide, self.solver) = (law, slide, solver);
        }
        self.core.set_params(self.slide, [settings.finger_damping; 2], settings.block);
        if from_silence {
            self.press(settings);
        }
        self.energy_at_pluck = self.energy();
        self.work_at_pluck = self.core.control_work();
        // Static energy of the pluck: ½F² x(L − x)/(T L) for a point force F at x, where the
        // finger is (on its way to a new pluck position, it plucks where it has got to).
        let force = pluck_force(strike.velocity);
        let (x, t) = (self.right.position, self.core.string().params().tension);
        self.reference_energy =
            (0.5 * force * force * x * (self.length - x) / (t * self.length)).max(f64::MIN_POSITIVE);
        self.motion = self.reference_energy;
        self.pluck = Some(0);
        self.plucking_force = force;
        self.sounding = true;
        self.started = now;
    }

    /// Set the note's tuning (semitones; the caller sanitizes it).
    pub fn set_tuning(&mut self, semitones: f64, settings: &Settings) {
        self.tuning = semitones;
        self.settle_if_fresh(settings);
    }

    /// Set the note's polyphonic modulation offset of `param` (in the setting's unit; the caller
    /// sanitizes it).
    pub fn set_offset(&mut self, param: NoteParam, offset: f64, settings: &Settings) {
        match param {
            NoteParam::SlidePosition => self.slide_offset = offset,
            NoteParam::HandHeight => self.hand_offset = offset,
        }
        self.settle_if_fresh(settings);
    }

    /// A voice plucked from silence that has not rendered yet starts where its note's tuning and
    /// offsets put the slide, as if they had come with the note-on.
    fn settle_if_fresh(&mut self, settings: &Settings) {
        if self.fresh && self.sounding {
            self.lift_to(self.scale.position(self.semitones(settings)), settings);
            self.press(settings);
            self.energy_at_pluck = self.energy();
        }
    }

    /// A note from silence, its slide at rest where [`lift_to`](Self::lift_to) put it: string,
    /// slide, hand and body start in the scheme's static equilibrium under the note's hand
    /// height, the left finger resting on the string with [`REST_FORCE`] unless the hand holds
    /// the slide more than [`FINGER_LIFT`] above it, and the right finger off
    /// ([`SlideCore::rest_pressed`]): the slide pressed onto the string, or held still above it,
    /// so that nothing lands or settles and the note is the pluck's alone. The solver starts
    /// afresh from the compression and the force. Never allocates.
    fn press(&mut self, settings: &Settings) {
        let height = self.hand_height(settings, &self.channel);
        // As for a hand come down to `height`: the finger lifts only above `FINGER_LIFT`.
        let down = height <= FINGER_LIFT;
        let trailing = if down { 1.0 } else { 0.0 };
        let share = trailing_finger(self.live.0.slide_position, self.left_width).1;
        let left_force = REST_FORCE * trailing * share;
        let still = SlideControls { hand_height: height, left_force, right_force: 0.0, ..self.live.0 };
        let solvers = &self.solvers;
        if self.core.rest_pressed(still, |y, nyquist| solvers.static_slope(y, nyquist)).is_some() {
            self.live.0 = still;
            (self.trailing, self.trail_down) = (trailing, down);
            self.hold_hand(height);
        } else {
            self.rest_lifted();
        }
        let (y, force, _) = self.core.contact();
        self.solvers.start_still(y, -force);
    }

    /// Glide to `key`, still held down at poly pressure `pressure`, as the key this voice plays is
    /// let go (following keys): legato, without a pluck. The note played is the held key's now:
    /// the released note's tuning and offsets go with it, and the held key's pressure is the
    /// voice's.
    pub fn return_to(&mut self, key: u8, pressure: f64) {
        self.strike.key = key;
        self.start_expression(pressure);
    }

    /// A new note's expression: poly pressure `pressure`, no brightness of its own, no tuning, no
    /// offsets.
    fn start_expression(&mut self, pressure: f64) {
        (self.poly_pressure, self.tuning, self.slide_offset, self.hand_offset) = (pressure, 0.0, 0.0, 0.0);
        self.brightness = None;
    }

    /// Release the key.
    pub fn key_up(&mut self) {
        self.key_down = false;
    }

    /// Release the key of a note on an MPE zone's member channel, whose state is `channel`
    /// now: the note keeps it as it rings out (a note let go already keeps what it had).
    pub fn key_up_keeping(&mut self, channel: &ChannelState) {
        self.key_up();
        self.kept_channel.get_or_insert(*channel);
    }

    /// Fade the output out over [`STEAL_TIME`] and fall silent, the string brought to rest and
    /// the note ending: a sounding voice given up to lighten the load. Whether it began to fade
    /// (not if silent or fading already).
    pub fn shed(&mut self, sample_rate: f64) -> bool {
        if !self.sounding || self.shedding() {
            return false;
        }
        self.shed_fade.start((STEAL_TIME * sample_rate).ceil() as usize);
        self.key_down = false;
        true
    }

    /// Whether the voice is being shed.
    pub fn shedding(&self) -> bool {
        self.shed_fade.is_fading()
    }

    /// How much the string moves (J): its kinetic energy, held with a 50 ms fall; what shedding
    /// ranks slide voices by.
    pub fn motion(&self) -> f64 {
        self.motion
    }

    /// Stop at once: the string and the slide at rest, the slide lifted off the string and the
    /// fingers off, and the contact solver started afresh there (EXP's ψ holding nothing), so
    /// that nothing of the note is heard in the next.
    pub fn silence(&mut self) {
        self.shed_fade.clear();
        self.guard_fade.clear();
        self.sounding = false;
        self.key_down = false;
        self.kept_channel = None;
        self.pluck = None;
        self.mute = 0.0;
        self.unweighed = 0;
        self.rest_lifted();
        let (_, y) = self.core.compressions();
        self.solvers.start_still(y, 0.0);
    }

    /// As made under `settings`, but for the guitar it was last on and the guard's count of
    /// trips: silent, its controls at rest where `settings` put them, with no note started and
    /// the energy weighed afresh.
    pub fn reset(&mut self, settings: &Settings) {
        self.guard_fade.clear();
        let rest = Self::at_rest((self.length, self.left_width), &self.scale, settings);
        self.live.0 = rest;
        self.slide_motion = Motion::at_rest(rest.slide_position);
        self.right = Motion::at_rest(rest.right_position);
        self.follow_key = settings.follow_key;
        // The rest is lifted already, so silencing brings the core to rest on it.
        self.silence();
        self.core.restart();
        self.glided = 0.0;
        self.fresh = false;
        self.started = 0;
        self.unweighed = 0;
    }

    /// Energy of the string, the slide and the contact (J).
    pub fn energy(&self) -> f64 {
        let (y_prev, y_now) = self.core.compressions();
        self.core.energy() + self.solvers.stored_energy(y_now, y_prev)
    }

    /// How many times the guard has silenced this voice.
    pub fn guard_trips(&self) -> u32 {
        self.trips
    }

    /// The part of the slide position (semitones) that keys and bends ask for: the played key's
    /// distance from the open string when following keys, plus the bends of its channel and of
    /// its MPE zone's master channel.
    fn keys_and_bends(&self, settings: &Settings, channel: &ChannelState) -> f64 {
        let key = if self.follow_key { f64::from(self.strike.key) - f64::from(OPEN_KEY) } else { 0.0 };
        key + channel.bend * channel.bend_range.unwrap_or(settings.bend_range) + channel.zone_bend
    }

    /// The slide position (semitones above the open string): the glided keys and bends, plus the
    /// note's tuning, plus the `slide_position` setting (with the note's offset, clamped to its
    /// 0..=24 range) as it comes when not following keys.
    fn semitones(&self, settings: &Settings) -> f64 {
        self.glided + self.tuning + self.setting_part(settings, self.follow_key)
    }

    /// The part of the slide position (semitones) the `slide_position` setting gives, with the
    /// note's offset, clamped to its 0..=24 range: none when following keys.
    fn setting_part(&self, settings: &Settings, follow_key: bool) -> f64 {
        if follow_key { 0.0 } else { (settings.slide_position + self.slide_offset).clamp(0.0, 24.0) }
    }

    /// The hand height (m) the setting, with the note's offset, or the controller chosen for it
    /// asks for.
    fn hand_height(&self, settings: &Settings, channel: &ChannelState) -> f64 {
        let pressed = |v: f64| HAND_RANGE.0 + (HAND_RANGE.1 - HAND_RANGE.0) * v.clamp(0.0, 1.0);
        match settings.hand_source {
            HandSource::Parameter => {
                (settings.hand_height + self.hand_offset).clamp(-HAND_HEIGHT_LIMIT, HAND_HEIGHT_LIMIT)
            }
            HandSource::ModWheel => pressed(channel.mod_wheel),
            HandSource::ChannelPressure => pressed(channel.pressure),
            HandSource::PolyPressure => pressed(self.poly_pressure),
            HandSource::Timbre => pressed(self.brightness.or(channel.timbre).unwrap_or(0.0)),
        }
    }

    /// Take up `settings`' choice between following keys and the `slide_position` setting: the
    /// slide stays where it is and glides from there to where the new choice puts it, as keys
    /// glide, rather than adding or losing the setting's part at once.
    fn follow(&mut self, settings: &Settings) {
        if settings.follow_key != self.follow_key {
            self.glided +=
                self.setting_part(settings, self.follow_key) - self.setting_part(settings, settings.follow_key);
            self.follow_key = settings.follow_key;
        }
    }

    /// Whether the guard must silence the voice: its state is not finite, or its energy `energy`
    /// (J) is far above its bound (module docs).
    fn over_budget(&self, energy: f64) -> bool {
        let supplied = (self.core.control_work() - self.work_at_pluck).max(0.0);
        let bound = self.energy_at_pluck + supplied + self.reference_energy;
        !(energy.is_finite() && energy <= GUARD_FACTOR * bound)
    }

    /// Silence the voice at once, counted as a trip: the string at rest and the slide lifted off
    /// it, the fingers off.
    fn trip(&mut self) {
        self.trips += 1;
        self.silence();
        // The books of a state gone wrong may hold NaN, which would blind the guard's bound to
        // the work later notes supply.
        self.core.open_books();
    }

    /// A silent voice's slide at rest at `x_o` (m), lifted, its trailing finger behind it and the
    /// plucking finger where `settings` put it: where a note from silence starts, so that neither
    /// first travels there from where the voice last sounded.
    fn lift_to(&mut self, x_o: f64, settings: &Settings) {
        self.slide_motion = Motion::at_rest(x_o);
        let (left_position, right_position) =
            (trailing_finger(x_o, self.left_width).0, pluck_point(settings.pluck_position, x_o, self.length));
        self.right = Motion::at_rest(right_position);
        self.mute = 0.0;
        self.live.0 = SlideControls { slide_position: x_o, left_position, right_position, ..self.live.0 };
        self.rest_lifted();
    }

    /// Bring the string and the slide to rest, the slide lifted and the fingers off.
    fn rest_lifted(&mut self) {
        let lifted = SlideControls { hand_height: HAND_RANGE.0, left_force: 0.0, right_force: 0.0, ..self.live.0 };
        self.live.0 = lifted;
        (self.trailing, self.trail_down) = (0.0, false);
        self.corners = Corners::NONE;
        self.hold_hand(lifted.hand_height);
        self.core.set_body(self.body == SlideBody::Acoustic, lifted);
    }

    /// The hand at rest at `height` (m).
    fn hold_hand(&mut self, height: f64) {
        self.hand = Motion::at_rest(height);
        self.hand_path = HandPath::at_rest(height);
    }

    /// Whether it was plucked from silence and has not begun a control block since: it then
    /// begins one at once, for what is left of the instrument's, so that its note sounds from its
    /// own sample.
    pub fn fresh(&self) -> bool {
        self.fresh && self.sounding
    }

    /// Whether its finger is still plucking its latest note ([`PLUCK_TIME`]).
    pub fn plucking(&self) -> bool {
        self.pluck.is_some()
    }

    /// Work at a control-block boundary: move the controls on for the coming `len` samples and
    /// release the voice once silent.
    pub fn begin_block(&mut self, settings: &Settings, channel: &ChannelState, len: usize) {
        if !self.sounding {
            return;
        }
        let channel = &match self.kept_channel {
            Some(kept) => ChannelState { zone_bend: channel.zone_bend, ..kept },
            None => *channel,
        };
        if self.guard_fade.is_fading() {
            self.trip();
            return;
        }
        if self.shed_fade.is_silent() {
            self.silence();
            return;
        }
        // A note let go only: a note played since on this voice is not muted.
        if !self.key_down && self.mute >= MUTED_LIMIT {
            self.shed(self.core.string().sample_rate());
        }
        // A note from silence not rendered yet starts where the channel and the note ask for the
        // hand now: pressure and controllers arrive with the note-on or right after it.
        if self.fresh && self.hand_height(settings, channel) != self.hand.position {
            self.channel = *channel;
            self.settle_if_fresh(settings);
        }
        self.fresh = false;
        let fs = self.core.string().sample_rate();
        let span = len as f64 / fs;
        self.follow(settings);
        let target = self.keys_and_bends(settings, channel);
        self.glided += (target - self.glided) * self.glide_factor.get(-span / settings.glide_time, |x| 1.0 - x.exp());
        // Arrive: an exponential glide never quite does, and a moving slide costs a recomputation
        // of the contact vectors every block (or piece).
        if (target - self.glided).abs() < 1e-4 {
            self.glided = target;
        }
        let scale = &self.scale;
        let x_o = self.position_at.get(self.semitones(settings), |semitones| scale.position(semitones));
        self.slide_motion.approach(x_o, span, SLIDE_REACH, Passing::Turning);
        self.slide_motion.stop_within(self.scale.range());
        let hand_height = self.hand_height(settings, channel);
        // The slide rides on the hand's path, which runs behind the plan: the gap the plan has
        // left is the slide's less the path's lag.
        let gap = -self.core.compressions().1 - (self.hand_path.height - self.hand.position);
        let reach = hand_reach(&self.hand, hand_height, gap);
        self.hand.approach(hand_height, span, reach, Passing::Never);
        let hand = self.hand_path.follow(self.hand.position, span, reach);
        // The slide of the current note, its hand stilling it as the finger mutes the string.
        let mut slide = self.slide;
        let (from, plucked) = (self.live.0, self.pluck);
        let corners = pluck_corners(fs);
        let full = self.plucking_force;
        let mut finger_damping = [settings.finger_damping; 2];
        let right_force = match plucked {
            Some(t) => {
                self.pluck = Some(t + len).filter(|&n| n < corners[1]);
                full * pluck_share(t + len, corners)
            }
            None if self.key_down => 0.0,
            None => {
                self.mute += span;
                let landed = landed((self.mute / MUTE_TIME).min(1.0));
                slide.damping = slide.damping.max(MUTE_HAND_DAMPING * landed);
                finger_damping[1] = finger_damping[1].max(MUTE_FINGER_DAMPING * landed);
                REST_FORCE * landed
            }
        };
        let plucking = pluck_point(settings.pluck_position, self.slide_motion.position, self.length);
        self.right.approach(plucking, span, SLIDE_REACH, Passing::Never);
        // The trailing finger rests on the string while the hand holds the slide on it.
        if self.hand.position <= 0.0 {
            self.trail_down = true;
        } else if self.hand.position > FINGER_LIFT {
            self.trail_down = false;
        }
        let step = if self.trail_down { span } else { -span } / MUTE_TIME;
        self.trailing = (self.trailing + step).clamp(0.0, 1.0);
        let x_o = self.slide_motion.position;
        let (left_position, share) = trailing_finger(x_o, self.left_width);
        self.live.0 = SlideControls {
            slide_position: x_o,
            hand_height: hand.to,
            left_position,
            left_force: REST_FORCE * landed(self.trailing) * share,
            right_position: self.right.position,
            right_force,
        };
        self.core.set_params(slide, finger_damping, settings.block);
        self.corners = Corners::NONE;
        match plucked {
            Some(t) => self.cut_at_corners(from, t, len, corners, full, hand),
            None => {
                self.core.bow_hand(hand.sag);
                self.core.start_block(len);
            }
        }
        // The energies take a pass over the modes: every block, or every `ENERGY_INTERVAL`
        // samples when the blocks are shorter.
        self.unweighed += len;
        if self.unweighed < ENERGY_INTERVAL {
            return;
        }
        let since = self.unweighed as f64 / fs;
        self.unweighed = 0;
        // The guard leaves out the contact's small share (below the bound, which includes it).
        let (kinetic, energy) = self.core.energies();
        if self.over_budget(energy) {
            self.guard_fade.start(len);
        }
        // A pressed slide holds static energy in the string and the hand for ever, so silence is
        // judged on the string's motion.
        self.motion = kinetic.max(self.motion * self.motion_factor.get(-since / 0.05, f64::exp));
        // A voice caught over its bound trips at the next block instead (and is counted).
        let quiet = self.motion < RELEASE_ENERGY * self.reference_energy;
        if !self.key_down && self.pluck.is_none() && quiet && !self.guard_fade.is_fading() {
            // At rest and lifted, as a voice never played: the next note on it starts as on a
            // fresh voice, not with the slide pressed where this one left it.
            self.silence();
        }
    }

    /// Begin a control block of `len` samples from the controls `from` to those set for its end,
    /// `t` samples into a pluck of `full` force (N) with `corners`, the hand on the path `hand`:
    /// cut at the corners that fall inside it, each piece's controls on the block's ramps and
    /// the hand on its path, but for the force, which is the pluck's own at every corner.
    fn cut_at_corners(&mut self, from: SlideControls, t: usize, len: usize, corners: [usize; 2], full: f64, hand: Bow) {
        let end = self.live.0;
        let mut cuts = corners.into_iter().filter(|&c| t < c && c < t + len).map(|c| c - t);
        let Some(first) = cuts.next() else {
            self.core.bow_hand(hand.sag);
            self.core.start_block(len);
            return;
        };
        let share = |k: usize| k as f64 / len as f64;
        let at = |k: usize| SlideControls {
            hand_height: hand.at(share(k)),
            right_force: full * pluck_share(t + k, corners),
            ..from.lerp(&end, share(k))
        };
        let piece = |k: usize, length: usize| (length, at(k), hand.sag_of_part(share(length)));
        let second = cuts.next();
        let after = second.unwrap_or(first);
        let last = (len - after, end, hand.sag_of_part(share(len - after)));
        self.corners = Corners { pieces: [second.map(|c| piece(c, c - first)), Some(last)], left: first };
        self.live.0 = at(first);
        self.core.bow_hand(hand.sag_of_part(share(first)));
        self.core.start_block(first);
    }

    /// The string, for monitoring.
    pub fn string(&self) -> &ModalString {
        self.core.string()
    }

    /// The weights the core reaches the string's modes through, for monitoring: the string's
    /// shape is `Σ w_i sin(β_i x) ũ_i` ([`ModalString::displacement_at`]).
    pub fn coupling_weights(&self) -> Option<&[f64]> {
        self.core.coupling_weights()
    }

    /// `(compression (m), latest contact force (N), slide position (fraction of the length))`.
    pub fn contact(&self) -> (f64, f64, f64) {
        let (y, f, x) = self.core.contact();
        (y, f, x / self.length)
    }

    /// Whether the slide touches the string (now or one step back).
    pub fn in_contact(&self) -> bool {
        self.core.in_contact()
    }

    /// Move the pickup to `position` (fraction of the length), gliding over the next `samples`
    /// samples.
    pub fn set_pickup(&mut self, position: f64, samples: usize) {
        self.pickup = position;
        self.core.set_pickup(Pickup { kind: OutputKind::Velocity, position, aperture: PICKUP_APERTURE }, samples);
    }

    /// Where the pickup is (fraction of the length): the last position [`set_pickup`](Self::set_pickup)
    /// moved it to.
    pub fn pickup(&self) -> f64 {
        self.pickup
    }

    /// Render `out.len()` samples of string velocity at the pickup (m/s, see
    /// [`SLIDE_SCALE`](crate::instrument::SLIDE_SCALE)) or, on the acoustic body, of what the
    /// body radiates ([`ACOUSTIC_SCALE`](crate::instrument::ACOUSTIC_SCALE)). A voice the guard
    /// has caught fades out linearly over its block; a non-finite sample silences it at once, and
    /// the samples rendered with it are silent.
    pub fn render(&mut self, out: &mut [f64]) {
        self.render_parts(out, None);
    }

    /// [`render`](Self::render), with the shares of the output that the body's modes heard on
    /// the left and on the right radiated in `sides` (slices as long as `out`; zero on the
    /// electric guitar), faded and silenced with it.
    pub fn render_sides(&mut self, out: &mut [f64], sides: [&mut [f64]; 2]) {
        self.render_parts(out, Some(sides));
    }

    fn render_parts(&mut self, out: &mut [f64], mut sides: Option<[&mut [f64]; 2]>) {
        let mut done = 0;
        while done < out.len() {
            // The next piece begins at its first step, not at the end of the call before: a note
            // played between the host's calls sets the core's block length for the next block.
            if self.corners.left == 0
                && let Some((len, controls, sag)) = self.corners.take()
            {
                self.live.0 = controls;
                self.core.bow_hand(sag);
                self.core.start_block(len);
                self.corners.left = len;
            }
            let pending = self.corners.pending();
            let run = if pending { self.corners.left.min(out.len() - done) } else { out.len() - done };
            let span = done..done + run;
            let s = &mut self.solvers;
            let parts = sides.as_mut().map(|[l, r]| [&mut l[span.clone()], &mut r[span.clone()]]);
            let out = &mut out[span];
            match s.method {
                Method::Qsa => self.core.process_output(&mut s.qsa, &mut self.live, out, parts),
                Method::Imp => self.core.process_output(&mut s.imp, &mut self.live, out, parts),
                Method::Exp => self.core.process_output(&mut s.exp, &mut self.live, out, parts),
            }
            done += run;
            if pending {
                self.corners.left -= run;
            }
        }
        let finite = |x: &[f64]| x.iter().all(|x| x.is_finite());
        if !(finite(out) && sides.iter().flatten().all(|x| finite(x))) {
            out.fill(0.0);
            sides.iter_mut().flatten().for_each(|x| x.fill(0.0));
            self.trip();
        } else {
            match sides {
                None => {
                    self.guard_fade.apply(out);
                    self.shed_fade.apply(out);
                }
                Some([left, right]) => {
                    self.guard_fade.apply_together([&mut *out, &mut *left, &mut *right]);
                    self.shed_fade.apply_together([out, left, right]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64;

    use super::*;

    const FS: f64 = 44100.0;

    /// The note the tests' voices pluck: key 52 at velocity 0.8.
    const STRIKE: Strike = Strike { channel: 0, key: 52, velocity: 0.8, shifted: false, timbre: None };

    /// The trailing finger rests only on the dead part of the string, between the nut and the
    /// slide: wherever it lays any force its window lies within them, and its force grows with
    /// the slide's position without a step. A note on the open string's key (its slide 5 mm from
    /// the nut) rests no finger there (2 mm from the nut, its window would reach past the nut and
    /// 4.5 mm under the speaking string); on D3 the finger rests with its whole force, clear of
    /// both.
    #[test]
    fn the_trailing_finger_rests_only_on_the_dead_part_of_the_string() {
        let width = crate::preset::slide_guitar().left.width;
        let mut last = 0.0;
        for i in 0..=2_000 {
            let x_o = 1e-4 * f64::from(i);
            let (at, share) = trailing_finger(x_o, width);
            if share > 0.0 {
                assert!(at - 0.5 * width >= 0.0 && at + 0.5 * width <= x_o, "x_o {x_o}: window at {at}");
            }
            assert!((share - last).abs() <= 1e-4 / (0.5 * width) + 1e-12, "x_o {x_o}: share {last} to {share}");
            last = share;
        }
        for (key, force) in [(45, 0.0), (50, REST_FORCE)] {
            let settings = Settings { mode: crate::instrument::Mode::Slide, ..Settings::default() };
            let mut voice = SlideVoice::new(FS, &settings);
            let channel = ChannelState::default();
            voice.play(Strike { key, ..STRIKE }, &settings, &channel, false, 0);
            for _ in 0..5 {
                voice.begin_block(&settings, &channel, 64);
                voice.render(&mut [0.0; 64]);
            }
            let controls = voice.live.0;
            assert!((controls.left_force - force).abs() <= 1e-12, "key {key}: {controls:?}");
            if force > 0.0 {
                let window = (controls.left_position - 0.5 * width, controls.left_position + 0.5 * width);
                assert!(window.0 >= 0.0 && window.1 <= controls.slide_position, "key {key}: {controls:?}");
            }
        }
    }

    /// A note's QSA fit spans twice the largest static push its hand can make, the `hand_height`
    /// setting's deepest press (3 mm, beyond a controller's 2 mm) included: the force at the
    /// fit's reference compression is `2(k_H (3 mm + 1 mm) + F_pluck + F_rest)` to rounding.
    #[test]
    fn a_notes_contact_fit_spans_the_deepest_press_the_setting_makes() {
        let settings = Settings { mode: crate::instrument::Mode::Slide, hand_height: -3e-3, ..Settings::default() };
        let mut voice = SlideVoice::new(FS, &settings);
        voice.play(STRIKE, &settings, &ChannelState::default(), false, 0);
        let y_ref = voice.solvers.qsa.spline().reference_compression();
        let law = PowerLaw::new(settings.slide_kappa, settings.slide_alpha).unwrap();
        let push = 2.0 * (settings.hand_stiffness * (3e-3 + 1e-3) + pluck_force(1.0) + REST_FORCE);
        let reached = law.kappa() * y_ref.powf(law.alpha());
        assert!((reached / push - 1.0).abs() < 1e-9, "the fit reaches {reached} N, the push is {push} N");
    }

    /// The monitor draws the string as the core reaches it: through the coupling weights, the
    /// shape at `x` is the state's projection on the weighted mode shapes there (to 1e-10 of
    /// itself), which the unweighted sum is not.
    #[test]
    fn the_string_is_drawn_through_the_cores_weights() {
        let (mut voice, settings) = plucked(0);
        let channel = ChannelState::default();
        let mut out = [0.0; 64];
        for _ in 0..5 {
            voice.begin_block(&settings, &channel, 64);
            voice.render(&mut out);
        }
        let (string, weights) = (voice.string(), voice.coupling_weights().expect("the voice weighs its modes"));
        let mut shape = string.vector();
        for x in [0.05, 0.3, 0.58] {
            string.mode_shapes(x, &mut shape);
            shape.iter_mut().zip(weights).for_each(|(h, w)| *h *= w);
            let expected = string.project_state(&shape).1;
            let drawn = string.displacement_at(x, Some(weights));
            assert!((drawn - expected).abs() <= 1e-10 * expected.abs(), "x = {x}: {drawn} against {expected}");
            assert_ne!(string.displacement_at(x, None), drawn, "x = {x}: the weights change the shape");
        }
    }

    /// The pluck's corners cut blocks into pieces of the voice's own; a host that splits the
    /// blocks into calls anywhere, through the pieces' ends too, hears the same samples to the
    /// bit over the 40 blocks of the pluck and after it.
    #[test]
    fn a_plucked_voice_rendered_in_any_chunks_sounds_the_same() {
        let (mut whole, settings) = plucked(0);
        let mut chunked = whole.clone();
        let channel = ChannelState::default();
        let mut rng = Pcg64::seed_from_u64(5);
        let mut worst = 0.0f64;
        for _ in 0..40 {
            let (mut a, mut b) = ([0.0; 64], [0.0; 64]);
            whole.begin_block(&settings, &channel, 64);
            whole.render(&mut a);
            chunked.begin_block(&settings, &channel, 64);
            let mut done = 0;
            while done < 64 {
                let n = rng.random_range(1..=64 - done);
                chunked.render(&mut b[done..done + n]);
                done += n;
            }
            worst = a.iter().zip(&b).fold(worst, |m, (x, y)| m.max((x - y).abs()));
        }
        assert_eq!(worst, 0.0);
    }

    /// A note played again between two host calls that meet at a corner of the pluck (at
    /// 44.1 kHz the force stops rising at sample 353, inside the block 320–383) leaves the next
    /// piece its length: the force keeps to its ramps, and the output's curvature (second
    /// difference) near the block's end, sample 384, stays within twice what a re-pluck one
    /// sample either side of the corner gives (measured equal). When the piece began at the end
    /// of the call before, the note's block length replaced the piece's, the ramps ran over a
    /// whole block, the force stepped by 0.6 N at the next block and the curvature rose 16-fold.
    #[test]
    fn a_note_played_again_at_a_corner_of_the_pluck_keeps_its_pieces() {
        let curvature = |split: usize| {
            let (mut voice, settings) = plucked(0);
            let channel = ChannelState::default();
            let mut out = vec![0.0; 64 * 10];
            for block in 0..10 {
                voice.begin_block(&settings, &channel, 64);
                let (from, to) = (64 * block, 64 * (block + 1));
                if (from..to).contains(&split) {
                    voice.render(&mut out[from..split]);
                    voice.play(STRIKE, &settings, &channel, false, 0);
                    voice.render(&mut out[split..to]);
                } else {
                    voice.render(&mut out[from..to]);
                }
            }
            (380..390).map(|i| (out[i + 1] - 2.0 * out[i] + out[i - 1]).abs()).fold(0.0, f64::max)
        };
        let at = curvature(353);
        let beside = curvature(352).max(curvature(354));
        assert!(at <= 2.0 * beside, "curvature {at:e} with the re-pluck at the corner, {beside:e} beside it");
    }

    /// The shortest time (s) in which a motion within `reach` covers `distance` (m) from rest to
    /// rest: speeding up at the limit `a` and braking at `BRAKING·a`, with a stretch at top speed
    /// if it is reached.
    fn shortest_time(distance: f64, reach: Reach) -> f64 {
        let (v, a, b) = (reach.speed, reach.acceleration, BRAKING * reach.acceleration);
        if distance < 0.5 * v * v * (1.0 / a + 1.0 / b) {
            (2.0 * distance * (a + b) / (a * b)).sqrt()
        } else {
            distance / v + 0.5 * v / a + 0.5 * v / b
        }
    }

    /// The hand's path follows its plan half a block behind without a jump of speed: the hand
    /// planned between random heights, lowering onto a string up to 2 mm below it, at blocks of
    /// 1 to 256 samples at 48 kHz. Each block's path starts at the last one's end speed
    /// (within 1e-9 m/s), changes its speed across the block by no more than the plan's speed
    /// changes between blocks, ends on the midpoint of the plan's block (within 1e-15 m, some
    /// thousands of doubles' spacings) and rests exactly on the plan's target once the plan
    /// rests there. Where the blocks change length while the hand moves (a random length once in
    /// each leg, 1 to 15 blocks in), the path's speed steps by at most the plan's reach `a·T` at
    /// a block boundary, stays within twice `HAND_SPEED`, and the path is back on the midpoints
    /// within 25 ms of the change (an offset of up to 1.3 mm taken back at 50 m/s² in about
    /// 11 ms, and a block of up to 5.3 ms).
    #[test]
    fn the_hands_path_follows_its_plan_half_a_block_behind_its_speed_never_jumping() {
        // The path's speed at the start of its block, from its parabola.
        let start_speed = |bow: &Bow, span: f64| (bow.to - bow.from - 4.0 * bow.sag) / span;
        for block in [1.0, 8.0, 64.0, 256.0] {
            let span = block / 48_000.0;
            let mut rng = Pcg64::seed_from_u64(31);
            let mut plan = Motion::at_rest(HAND_RANGE.0);
            let mut path = HandPath::at_rest(plan.position);
            let mut speed = 0.0;
            for leg in 0..200 {
                let target = rng.random_range(HAND_RANGE.1..HAND_RANGE.0);
                let gap = rng.random_range(0.0..2e-3);
                let mut blocks = 0;
                while plan.position != target || plan.velocity != 0.0 || path.height != target || path.velocity() != 0.0
                {
                    let (was, starting) = (plan.position, path.velocity());
                    let reach = hand_reach(&plan, target, gap);
                    plan.approach(target, span, reach, Passing::Never);
                    let bow = path.follow(plan.position, span, reach);
                    let what = format!("block {block}, leg {leg}, block {blocks}: {path:?}");
                    let jump = start_speed(&bow, span) - starting;
                    assert!(jump.abs() <= 1e-9, "{what}: the speed jumps by {jump} m/s");
                    let now = (plan.position - was) / span;
                    let change = (path.velocity() - starting).abs();
                    assert!(change <= (now - speed).abs() + 1e-9, "{what}: speed changes by {change} m/s");
                    speed = now;
                    let off = path.height - 0.5 * (was + plan.position);
                    assert!(off.abs() <= 1e-15, "{what}: {off} m off the plan's midpoint");
                    blocks += 1;
                    assert!(blocks < 100_000, "{what}: never arrives");
                }
            }
        }
        let mut rng = Pcg64::seed_from_u64(32);
        let mut plan = Motion::at_rest(HAND_RANGE.0);
        let mut path = HandPath::at_rest(plan.position);
        let mut span = 64.0 / 48_000.0;
        for leg in 0..500 {
            let target = rng.random_range(HAND_RANGE.1..HAND_RANGE.0);
            let switch = rng.random_range(1..=15);
            let (mut blocks, mut t, mut since, mut last_off) = (0, 0.0, 0.0, 0.0);
            while plan.position != target || plan.velocity != 0.0 || path.height != target || path.velocity() != 0.0 {
                if blocks == switch {
                    span = rng.random_range(1..=256) as f64 / 48_000.0;
                    since = t;
                }
                let (was, starting) = (plan.position, path.velocity());
                let reach = hand_reach(&plan, target, 1e-3);
                plan.approach(target, span, reach, Passing::Never);
                let bow = path.follow(plan.position, span, reach);
                let what = format!("leg {leg}, {span} s blocks, block {blocks}: {path:?}");
                let jump = start_speed(&bow, span) - starting;
                let most = reach.acceleration * span;
                assert!(jump.abs() <= most * (1.0 + 1e-9) + 1e-9, "{what}: jumps by {jump} m/s");
                assert!(path.velocity().abs() <= 2.0 * HAND_SPEED, "{what}: {} m/s", path.velocity());
                blocks += 1;
                t += span;
                if (path.height - 0.5 * (was + plan.position)).abs() > 1e-15 {
                    last_off = t;
                }
                assert!(blocks < 100_000, "{what}: never arrives");
            }
            assert!(last_off - since <= 0.025, "leg {leg}: off the midpoints {} s after the switch", last_off - since);
        }
    }

    /// The hand lowering the slide from 2 mm above the string to 1.5 mm into it slows down to
    /// [`LANDING_SPEED`] before the slide reaches the string, whatever the control block: planned
    /// with the gap its own height leaves (the slide riding on the plan), at blocks of 1, 16, 64
    /// and 256 samples at 44.1 kHz its speed where it crosses the string's line is within 5 % of
    /// the landing speed or below it (measured 0.0500 m/s at every block; under a bound of
    /// `v_land + √(2·a_l·d)` it was 0.054 m/s at 64 samples and 0.127 m/s at 256).
    #[test]
    fn the_hand_slows_to_the_landing_speed_before_the_string_at_every_block() {
        for block in [1.0, 16.0, 64.0, 256.0] {
            let span = block / 44_100.0;
            let mut hand = Motion::at_rest(2e-3);
            let target = -1.5e-3;
            let mut crossing = None;
            for _ in 0..100_000 {
                let was = hand.position;
                let reach = hand_reach(&hand, target, hand.position);
                hand.approach(target, span, reach, Passing::Never);
                if was > 0.0 && hand.position <= 0.0 {
                    crossing = Some((hand.position - was) / span);
                }
                if hand.position == target && hand.velocity == 0.0 {
                    break;
                }
            }
            let speed = crossing.expect("the hand crosses the string's line").abs();
            println!("blocks of {block}: {speed:.4} m/s at the string's line");
            assert!(speed <= 1.05 * LANDING_SPEED, "blocks of {block}: {speed} m/s");
        }
    }

    /// The hand from lifted (−2 mm) to pressed (+2 mm) and back, the slide along the string from
    /// 5 mm to 0.49 m and back, then 500 targets drawn at random, each held until the motion
    /// rests on it, at control blocks of 1, 8, 64 and 256 samples (48 kHz): the position's speed
    /// never above the reach's and never changing by more than its acceleration allows in a
    /// block, never past a target, and on it within one block of the shortest time.
    #[test]
    fn the_hand_and_the_slide_approach_their_targets_with_bounded_speed_and_acceleration() {
        for block in [1.0, 8.0, 64.0, 256.0] {
            let span = block / 48_000.0;
            let motions =
                [(HAND_REACH, Passing::Never, (-2e-3f64, 2e-3f64)), (SLIDE_REACH, Passing::Turning, (0.005, 0.49))];
            for (reach, passing, (near, far)) in motions {
                let dv = reach.acceleration * span;
                let mut rng = Pcg64::seed_from_u64(73);
                let (mut m, mut speed) = (Motion::at_rest(near), 0.0);
                for leg in 0..502 {
                    let target = match leg {
                        0 => far,
                        1 => near,
                        _ => rng.random_range(near.min(far)..near.max(far)),
                    };
                    let start = m.position;
                    let shortest = shortest_time((target - start).abs(), reach);
                    let mut blocks = 0;
                    while m.position != target || m.velocity != 0.0 {
                        let x = m.position;
                        m.approach(target, span, reach, passing);
                        let now = (m.position - x) / span;
                        let what = format!("block {block}, {reach:?}, leg {leg}: {m:?}");
                        assert!(now.abs() <= reach.speed * (1.0 + 1e-12), "{what}: {now} m/s");
                        assert!((now - speed).abs() <= dv * (1.0 + 1e-9), "{what}: {speed} → {now} m/s");
                        assert!((m.position - start).abs() <= (target - start).abs(), "{what}: past {target}");
                        speed = now;
                        blocks += usize::from(m.position != target);
                        assert!(blocks < 100_000, "{what}: never arrives");
                    }
                    let late = (blocks + 1) as f64 * span - shortest;
                    assert!(late <= span * (1.0 + 1e-9), "{reach:?}, leg {leg}: {late} s late");
                }
            }
        }
    }

    /// A target moving within the limits is followed exactly, at every block length: a vibrato
    /// of the slide from rest at its turning point (±3 mm at 6 Hz: 4.3 m/s² at most) is met at
    /// the end of every block, its speed changing block by block as the vibrato's does; a ramp at
    /// 0.5 m/s that stops short is met where it stops, never passed.
    #[test]
    fn a_slide_moving_within_its_limits_follows_its_target_exactly() {
        use std::f64::consts::PI;
        for block in [1.0, 8.0, 64.0, 256.0] {
            let span = block / 48_000.0;
            let vibrato = |t: f64| 0.2 + 3e-3 * (2.0 * PI * 6.0 * t).cos();
            let mut m = Motion::at_rest(vibrato(0.0));
            for n in 1..(0.5 / span) as usize {
                let v = m.velocity;
                m.approach(vibrato(n as f64 * span), span, SLIDE_REACH, Passing::Turning);
                assert_eq!(m.position, vibrato(n as f64 * span), "block {block}, step {n}");
                assert!(
                    (m.velocity - v).abs() <= (2.0 * PI * 6.0).powi(2) * 3e-3 * span * 1.01,
                    "block {block}: {v} → {m:?}"
                );
            }
            let ramp = |t: f64| (0.1 + 0.5 * t).min(0.2);
            let mut m = Motion::at_rest(0.1);
            for n in 1..(0.3 / span) as usize {
                m.approach(ramp(n as f64 * span), span, SLIDE_REACH, Passing::Turning);
                assert!(m.position <= 0.2, "block {block}: past the ramp's end: {m:?}");
            }
            assert_eq!((m.position, m.velocity), (0.2, 0.0), "block {block}: at rest on the ramp's end");
        }
    }

    /// A target that turns back towards a turning motion lagging it (a glide reversed before the
    /// slide arrives, a trill, a vibrato faster than the slide can follow) is passed and met
    /// again, the speed never changing by more than the acceleration allows in a block: with the
    /// slide's reach and the hand's, it chases targets moving at random speeds up to the top
    /// speed, turning back at random
    /// (about five times a second) and jumping at random (about once a second), never standing
    /// still, for 10 s at control blocks of 1, 8, 64 and 256 samples. Stopping on such a target
    /// kept the speed it had and went on past it in the next block.
    #[test]
    fn a_motion_chasing_a_target_that_turns_back_keeps_within_its_acceleration() {
        for block in [1.0, 8.0, 64.0, 256.0] {
            let span = block / 48_000.0;
            for (reach, (near, far)) in [(SLIDE_REACH, (0.005f64, 0.49f64)), (HAND_REACH, (-2e-3, 2e-3))] {
                let dv = reach.acceleration * span;
                let mut rng = Pcg64::seed_from_u64(74);
                let mut m = Motion::at_rest(near);
                let (mut target, mut target_speed, mut speed) = (near, reach.speed, 0.0);
                let mut worst = 0.0f64;
                for n in 0..(10.0 / span) as usize {
                    if rng.random_bool((span * 1.0).min(1.0)) {
                        target = rng.random_range(near..far);
                    }
                    if rng.random_bool((span * 5.0).min(1.0)) {
                        target_speed = -target_speed.signum() * rng.random_range(0.1..1.0) * reach.speed;
                    }
                    if !(near..=far).contains(&(target + target_speed * span)) {
                        target_speed = -target_speed;
                    }
                    target += target_speed * span;
                    let x = m.position;
                    m.approach(target, span, reach, Passing::Turning);
                    let now = (m.position - x) / span;
                    let what = format!("block {block}, {reach:?}, step {n}: target {target}, {m:?}");
                    assert!(now.abs() <= reach.speed * (1.0 + 1e-12), "{what}: {now} m/s");
                    assert!((now - m.velocity).abs() <= 1e-9 * reach.speed, "{what}: moved at {now} m/s");
                    worst = worst.max((now - speed).abs() / dv);
                    assert!((now - speed).abs() <= dv * (1.0 + 1e-9), "{what}: {speed} → {now} m/s");
                    speed = now;
                }
                println!("block {block}, {reach:?}: largest change of speed {worst:.3} of the limit");
            }
        }
    }

    /// A slide following a target that speeds towards the nut (1.8 m/s at 10.2 mm, within the
    /// limits, so it is met at every block) and turns straight back passes the turn by up to
    /// `v²/(2a)` = 16 mm, which would take it past the nut; it stops against the scale's end
    /// (5 mm) instead, and follows the target back up.
    #[test]
    fn a_slide_passing_a_turn_near_the_nut_stops_against_the_scales_end() {
        let span = 64.0 / 48_000.0;
        let range = (0.005, 0.52);
        let target = |t: f64| if t <= 0.1 { 0.1 - 0.0898 * (t / 0.1).powi(2) } else { 0.0102 + 1.8 * (t - 0.1) };
        let mut m = Motion::at_rest(target(0.0));
        let mut lowest = f64::INFINITY;
        for n in 1..(0.3 / span) as usize {
            let t = n as f64 * span;
            m.approach(target(t), span, SLIDE_REACH, Passing::Turning);
            m.stop_within(range);
            lowest = lowest.min(m.position);
            if t < 0.099 {
                assert_eq!(m.position, target(t), "followed at {t} s");
            }
        }
        println!("lowest {lowest} m");
        assert_eq!(lowest, range.0, "the slide stops against the scale's end");
        assert!(m.position > 0.2, "the slide follows the target back up: {m:?}");
    }

    /// A voice plucked and rendered for `blocks` blocks of the default 64 samples.
    fn plucked(blocks: usize) -> (SlideVoice, Settings) {
        plucked_on(SlideBody::Pickup, blocks)
    }

    /// [`plucked`] on the guitar `body`.
    fn plucked_on(body: SlideBody, blocks: usize) -> (SlideVoice, Settings) {
        plucked_with(Settings { slide_body: body, ..Settings::default() }, blocks)
    }

    /// [`plucked_on`] under `settings` (in slide mode).
    fn plucked_with(settings: Settings, blocks: usize) -> (SlideVoice, Settings) {
        let settings = Settings { mode: crate::instrument::Mode::Slide, ..settings };
        let mut voice = SlideVoice::new(FS, &settings);
        voice.play(STRIKE, &settings, &ChannelState::default(), false, 0);
        let mut out = [0.0; 64];
        for _ in 0..blocks {
            voice.begin_block(&settings, &ChannelState::default(), 64);
            voice.render(&mut out);
        }
        (voice, settings)
    }

    /// Put `voice` far over its energy bound: a bound made a million times too small.
    fn over_its_bound(voice: &mut SlideVoice) {
        voice.energy_at_pluck = voice.energy() * 1e-7 / GUARD_FACTOR;
        voice.reference_energy = 0.0;
        voice.work_at_pluck = voice.core.control_work() + 1.0;
    }

    /// Give `voice`'s string a non-finite state.
    fn corrupt(voice: &mut SlideVoice) {
        let bad = vec![f64::NAN; voice.core.string().modes()];
        voice.core.string_mut().set_state(&bad, &bad);
    }

    /// A healthy voice stays well inside its bound: its energy after the pluck is far below
    /// [`GUARD_FACTOR`] times the pluck's energy plus the controls' work (in fact below the bound
    /// itself, as the balance says: measured 0.036 of it after 100 blocks).
    #[test]
    fn a_plucked_voice_stays_inside_its_energy_bound() {
        let (voice, _) = plucked(100);
        let supplied = (voice.core.control_work() - voice.work_at_pluck).max(0.0);
        let bound = voice.energy_at_pluck + supplied + voice.reference_energy;
        println!("energy {:e} J of bound {bound:e} J", voice.energy());
        assert!(voice.energy() <= bound, "{} > {bound}", voice.energy());
        assert!(!voice.over_budget(voice.energy()));
    }

    /// A voice whose energy exceeds its bound by more than [`GUARD_FACTOR`] (here: a bound made
    /// a million times too small) fades out linearly over the next block (each sample no louder
    /// than the same sample unfaded times the fade's gain, and the block's last sample within
    /// 1/64 of silence), then rests silent with its string at rest, and the trip is counted.
    #[test]
    fn the_guard_fades_a_voice_over_its_bound_within_one_block() {
        let (mut voice, settings) = plucked(20);
        let (mut faded, mut plain) = ([0.0; 64], [0.0; 64]);
        let mut twin = voice.clone();
        twin.begin_block(&settings, &ChannelState::default(), 64);
        twin.render(&mut plain);
        over_its_bound(&mut voice);
        voice.begin_block(&settings, &ChannelState::default(), 64);
        voice.render(&mut faded);
        for (i, (f, p)) in faded.iter().zip(&plain).enumerate() {
            assert_eq!(*f, p * (1.0 - i as f64 / 64.0), "sample {i}");
        }
        voice.begin_block(&settings, &ChannelState::default(), 64);
        assert!(!voice.sounding);
        assert_eq!(voice.guard_trips(), 1);
        assert_eq!(voice.core.string().energy(), 0.0, "the string is at rest");
    }

    /// A voice silenced (all sound off) while the guard fades it plays its next note: the fade and
    /// the trip it leads to were the old note's.
    #[test]
    fn a_voice_silenced_during_a_guard_fade_plays_its_next_note() {
        let (mut voice, settings) = plucked(20);
        over_its_bound(&mut voice);
        let mut out = [0.0; 64];
        voice.begin_block(&settings, &ChannelState::default(), 64);
        voice.render(&mut out);
        voice.silence();
        voice.play(
            Strike { channel: 0, key: 50, velocity: 0.8, shifted: false, timbre: None },
            &settings,
            &ChannelState::default(),
            false,
            0,
        );
        let mut peak: f64 = 0.0;
        for _ in 0..8 {
            voice.begin_block(&settings, &ChannelState::default(), 64);
            voice.render(&mut out);
            peak = out.iter().fold(peak, |m, x| m.max(x.abs()));
        }
        assert!(voice.sounding && peak > 0.0, "the new note sounds (peak {peak:e})");
        assert_eq!(voice.guard_trips(), 0);
    }

    /// A note played on a voice the guard is fading, legato or not, sounds: the old note's trip
    /// is counted and the new one is plucked from silence, as on a fresh voice to the bit.
    #[test]
    fn a_note_played_during_a_guard_fade_sounds_from_silence() {
        let strike = Strike { channel: 0, key: 50, velocity: 0.8, shifted: false, timbre: None };
        let channel = ChannelState::default();
        let run = |voice: &mut SlideVoice, settings: &Settings| {
            let mut out = [0.0; 64];
            (0..8)
                .flat_map(|_| {
                    voice.begin_block(settings, &channel, 64);
                    voice.render(&mut out);
                    out
                })
                .collect::<Vec<_>>()
        };
        let (mut fresh, settings) = plucked(0);
        fresh.silence();
        fresh.play(strike, &settings, &channel, false, 0);
        let expected = run(&mut fresh, &settings);
        assert!(expected.iter().any(|&x| x != 0.0));
        for legato in [false, true] {
            let (mut voice, settings) = plucked(20);
            over_its_bound(&mut voice);
            let mut out = [0.0; 64];
            voice.begin_block(&settings, &channel, 64);
            voice.render(&mut out);
            voice.play(strike, &settings, &channel, legato, 0);
            assert_eq!(voice.guard_trips(), 1, "legato {legato}");
            assert_eq!(run(&mut voice, &settings), expected, "legato {legato}");
        }
    }

    /// With a control block of one sample the guard weighs the energy every [`ENERGY_INTERVAL`]
    /// samples, not every block: a voice over its bound is caught within that many samples and
    /// faded out in the block that follows.
    #[test]
    fn the_guard_weighs_one_sample_blocks_every_energy_interval() {
        let (mut voice, settings) = plucked(20);
        over_its_bound(&mut voice);
        let mut out = [0.0; 1];
        let mut blocks = 0;
        while voice.sounding && blocks < 2 * ENERGY_INTERVAL {
            voice.begin_block(&settings, &ChannelState::default(), 1);
            voice.render(&mut out);
            blocks += 1;
        }
        println!("silenced after {blocks} one-sample blocks");
        assert!(!voice.sounding, "still sounding after {blocks} blocks");
        assert!(blocks <= ENERGY_INTERVAL + 1, "{blocks} blocks");
        assert_eq!(voice.guard_trips(), 1);
    }

    /// On the acoustic body the shares of the output from the modes on either side are rendered
    /// with it, and the guard treats them as the output: a voice over its bound fades all three
    /// by the same gain at each sample, and a non-finite state silences all three at once.
    #[test]
    fn the_sides_of_the_acoustic_body_fade_and_fall_silent_with_the_voice() {
        let render = |voice: &mut SlideVoice, settings: &Settings| {
            let (mut out, mut left, mut right) = ([0.0; 64], [0.0; 64], [0.0; 64]);
            voice.begin_block(settings, &ChannelState::default(), 64);
            voice.render_sides(&mut out, [&mut left, &mut right]);
            [out, left, right]
        };
        let (mut voice, settings) = plucked_on(SlideBody::Acoustic, 20);
        let plain = render(&mut voice.clone(), &settings);
        for (i, share) in plain.iter().enumerate() {
            assert!(share.iter().all(|x| x.is_finite()) && share.iter().any(|&x| x != 0.0), "signal {i}");
        }
        let mut tripped = voice.clone();
        over_its_bound(&mut tripped);
        let faded = render(&mut tripped, &settings);
        for (f, p) in faded.iter().zip(&plain) {
            for (i, (f, p)) in f.iter().zip(p).enumerate() {
                assert_eq!(*f, p * (1.0 - i as f64 / 64.0), "sample {i}");
            }
        }
        corrupt(&mut voice);
        let silenced = render(&mut voice, &settings);
        assert!(silenced.iter().flatten().all(|&x| x == 0.0));
        assert!(!voice.sounding);
        assert_eq!(voice.guard_trips(), 1);
    }

    /// A non-finite state silences the voice in the same call: the samples are zero, not NaN,
    /// and the trip is counted. Its energy books start afresh, so the next note's bound counts the
    /// work the hand supplies, as on a fresh voice.
    #[test]
    fn a_non_finite_state_is_silenced_at_once() {
        let (mut voice, settings) = plucked(20);
        corrupt(&mut voice);
        let mut out = [1.0; 64];
        voice.render(&mut out);
        assert!(out.iter().all(|&x| x == 0.0));
        assert!(!voice.sounding);
        assert_eq!(voice.guard_trips(), 1);
        assert_eq!(voice.core.control_work(), 0.0);
        voice.play(STRIKE, &settings, &ChannelState::default(), false, 0);
        for _ in 0..20 {
            voice.begin_block(&settings, &ChannelState::default(), 64);
            voice.render(&mut out);
        }
        assert!(voice.core.control_work().is_finite() && voice.work_at_pluck.is_finite());
    }

    /// Silenced at once (all sound off), a ringing voice keeps nothing of its note: on either
    /// guitar and with each solver its string, slide, body and contact hold no energy (EXP's
    /// ψ too, which the pressed slide had charged), and the slide is lifted.
    #[test]
    fn a_silenced_voice_keeps_nothing_of_its_note() {
        for (body, method) in
            [SlideBody::Pickup, SlideBody::Acoustic].into_iter().flat_map(|b| Method::ALL.map(|m| (b, m)))
        {
            let (mut voice, _) = plucked_with(Settings { slide_body: body, method, ..Settings::default() }, 40);
            let ringing = voice.energy();
            assert!(ringing > 1e-6, "{body:?}: {ringing} J before");
            voice.silence();
            assert!(!voice.sounding);
            assert_eq!(voice.energy(), 0.0, "{body:?}, {method:?}: the energy left");
            assert_eq!(voice.core.compressions(), (-HAND_RANGE.0, -HAND_RANGE.0), "{body:?}: the slide lifted");
        }
    }

    /// A note from silence starts in the scheme's static equilibrium, the hand pressing the slide
    /// onto the string or holding it 0.6 mm above (the trailing finger resting on the string in
    /// both, below [`FINGER_LIFT`]) or 1.5 mm above (the finger off it too): played but not
    /// plucked (the plucking finger never comes), on both guitars and with each solver, the
    /// string, slide, hand and body stay still for 0.2 s: the output stays 100 dB below the
    /// pluck's peak and the energy (string, hand, contact, body) is constant to 1e-9 of itself,
    /// or, with nothing pushing the string aside, stays within rounding of 0 J: below 1e-20 J
    /// (measured 2e-26 J).
    /// (EXP starts in a still state its explicit gradient keeps still, ψ short of `√(2V(y))`
    /// ([`ExplicitSolver::still_force`](crate::contact::ExplicitSolver::still_force)): from the
    /// consistent one, a deviation of the compression alternating from step to step would double
    /// every step from rounding, the output 17 dB below the pluck within 0.2 s.)
    #[test]
    fn a_note_from_silence_starts_still() {
        for body in [SlideBody::Pickup, SlideBody::Acoustic] {
            let (mut plucked, _) = plucked_on(body, 0);
            let mut out = [0.0; 64];
            let mut pluck_peak = 0.0f64;
            for _ in 0..138 {
                plucked.begin_block(
                    &Settings { slide_body: body, ..Settings::default() },
                    &ChannelState::default(),
                    64,
                );
                plucked.render(&mut out);
                pluck_peak = out.iter().fold(pluck_peak, |m, v| m.max(v.abs()));
            }
            let pressing = Settings::default().hand_height;
            for (method, hand_height) in [Method::Qsa, Method::Imp, Method::Exp]
                .into_iter()
                .flat_map(|method| [(method, pressing), (method, 0.6e-3), (method, 1.5e-3)])
            {
                let mode = crate::instrument::Mode::Slide;
                let settings = Settings { mode, slide_body: body, method, hand_height, ..Settings::default() };
                let mut voice = SlideVoice::new(FS, &settings);
                voice.play(STRIKE, &settings, &ChannelState::default(), false, 0);
                voice.pluck = None;
                let (y, force, _) = voice.contact();
                let pressed = hand_height == pressing;
                assert!(
                    voice.in_contact() == pressed && (force < 0.0) == pressed,
                    "{body:?} {method:?}, hand at {hand_height:e} m: {y:e} m, {force} N"
                );
                let e0 = voice.energy();
                let mut peak = 0.0f64;
                let mut drift = 0.0f64;
                for _ in 0..138 {
                    voice.begin_block(&settings, &ChannelState::default(), 64);
                    voice.render(&mut out);
                    peak = out.iter().fold(peak, |m, v| m.max(v.abs()));
                    // Relative to the energy at rest, or, with nothing pushed aside, in joules.
                    let e = voice.energy();
                    drift = drift.max(if e0 > 0.0 { (e / e0 - 1.0).abs() } else { e.abs() });
                }
                let below = 20.0 * (pluck_peak / peak.max(1e-300)).log10();
                println!(
                    "{body:?} {method:?}, hand at {hand_height:e} m: y* = {y:.4e} m, F = {force:.4} N, E = {e0:.4e} J; \
                     output {below:.1} dB below the pluck, energy drift {drift:.2e}"
                );
                assert!(below > 100.0, "{body:?} {method:?}: {below} dB");
                let bound = if e0 > 0.0 { 1e-9 } else { 1e-20 };
                assert!(drift < bound, "{body:?} {method:?}: drift {drift:e}");
                assert_eq!(voice.guard_trips(), 0);
            }
        }
    }
}
