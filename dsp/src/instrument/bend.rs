//! How far a channel's pitch bend moves a slide: the registered parameters a controller sets
//! (MIDI 1.0's RPN protocol) and the zones of MPE.
//!
//! - **Pitch-bend sensitivity** (RPN 0): CC101 = 0 and CC100 = 0 select it, CC6 sets its
//!   semitones and CC38 its cents (sent alone, the cents refine the semitones the channel has,
//!   the setting's if never told). A full bend on that channel then moves the slide that far;
//!   a channel never told follows the `Bend range` setting. Sent on a member channel of an MPE
//!   zone, it sets every member channel of the zone (the per-note range is the zone's).
//! - **MPE configuration** (RPN 6, sent on MIDI channel 1 or 16, the zone's master channel): CC6
//!   gives the number of member channels of the lower zone (channels 2 up) or of the upper zone
//!   (channels 15 down), 0 ending the zone. As the MPE specification asks, configuring a zone sets
//!   its master's sensitivity to ±2 semitones and its members' to ±48; the master's bend then
//!   moves every note of the zone, on top of the note's own channel's bend. The zones never
//!   overlap: the zone configured last keeps its channels and the other shrinks to those left
//!   (of 16, each zone takes its master and members), or ends; ending a zone that is not there
//!   changes nothing.
//! - A configured zone's master channel speaks for the zone: its mod wheel and channel pressure
//!   are every member channel's too, until a member sends its own (the latest value wins).
//! - Any other parameter, or none selected (the null parameter, 127/127), takes no data; nor does
//!   a non-registered parameter (CC99 and CC98 select one, deselecting the registered one).
//!   Reset-all-controllers (CC121) deselects the parameter and keeps the values (MIDI RP-015).

/// The null parameter number (MSB, LSB): no parameter selected.
const NULL: (u8, u8) = (127, 127);

/// Pitch-bend sensitivity's parameter number.
const SENSITIVITY: (u8, u8) = (0, 0);

/// The MPE configuration message's parameter number.
const MPE_CONFIGURATION: (u8, u8) = (0, 6);

/// Sensitivity of an MPE zone's master channel and member channels once configured (semitones).
pub const MPE_MASTER_RANGE: f64 = 2.0;
/// See [`MPE_MASTER_RANGE`].
pub const MPE_MEMBER_RANGE: f64 = 48.0;

/// Each channel's selected parameter and bend range, and the MPE zones.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Bends {
    /// The parameter number each channel's data entry sets.
    selected: [(u8, u8); 16],
    /// Semitones of a full bend on each channel; `None` follows the setting.
    ranges: [Option<f64>; 16],
    /// Member channels of the lower zone (master MIDI channel 1) and the upper (master 16).
    members: [u8; 2],
}

impl Default for Bends {
    fn default() -> Self {
        Self { selected: [NULL; 16], ranges: [None; 16], members: [0; 2] }
    }
}

impl Bends {
    /// Controller `controller` of the RPN protocol (CC6, 38, 100 or 101, and CC98 and 99, which
    /// select a non-registered parameter) at `value` (0..=127) on `channel` (0..=15), with the
    /// `Bend range` setting at `setting` (semitones): cents sent alone refine the semitones the
    /// channel has, the setting's for a channel never told. Other controllers are ignored.
    pub(crate) fn controller(&mut self, channel: u8, controller: u8, value: u8, setting: f64) {
        let c = usize::from(channel & 15);
        let value = value & 127;
        match (controller, self.selected[c]) {
            (98 | 99, _) => self.selected[c] = NULL,
            (101, (_, lsb)) => self.selected[c] = (value, lsb),
            (100, (msb, _)) => self.selected[c] = (msb, value),
            (6, SENSITIVITY) => self.set_sensitivity(c, f64::from(value)),
            (38, SENSITIVITY) => {
                let semitones = self.ranges[c].unwrap_or(setting).trunc();
                self.set_sensitivity(c, semitones + f64::from(value) / 100.0);
            }
            (6, MPE_CONFIGURATION) if c == 0 || c == 15 => self.configure_zone(c, value.min(15)),
            _ => {}
        }
    }

    /// Channel `c`'s sensitivity at `semitones`; on a member channel of a configured zone, every
    /// member's (the MPE specification's per-note range is the zone's, and controllers send it
    /// on one member channel only).
    fn set_sensitivity(&mut self, c: usize, semitones: f64) {
        match self.master(c as u8) {
            Some(master) => {
                let master = usize::from(master);
                for m in Self::members_of(master, self.members[usize::from(master == 15)]) {
                    self.ranges[m] = Some(semitones);
                }
            }
            None => self.ranges[c] = Some(semitones),
        }
    }

    /// No parameter selected on any channel; the sensitivities and the zones stay (the device's
    /// configuration, which a controller sends once, as reset-all-controllers keeps it).
    pub(crate) fn deselect_all(&mut self) {
        self.selected = [NULL; 16];
    }

    /// Reset-all-controllers on `channel`: no parameter selected; the values stay.
    pub(crate) fn reset_controllers(&mut self, channel: u8) {
        self.selected[usize::from(channel & 15)] = NULL;
    }

    /// The zone mastered by channel `master` (0 or 15) takes `count` member channels (0 ends it);
    /// the other zone shrinks to the channels left, if it must.
    fn configure_zone(&mut self, master: usize, count: u8) {
        let zone = usize::from(master == 15);
        self.end_zone(zone);
        if count == 0 {
            return;
        }
        let other = 1 - zone;
        // Of 16 channels, the two masters and the members: 14 members at most between them.
        let left = 14u8.saturating_sub(count);
        if self.members[other] > left {
            self.end_zone(other);
            self.start_zone(other, left);
        }
        self.start_zone(zone, count);
    }

    /// The channels of zone `zone` (0 lower, 1 upper), if it is there, follow the setting again.
    fn end_zone(&mut self, zone: usize) {
        let master = 15 * zone;
        if self.members[zone] > 0 {
            self.ranges[master] = None;
            for c in Self::members_of(master, self.members[zone]) {
                self.ranges[c] = None;
            }
        }
        self.members[zone] = 0;
    }

    /// Zone `zone` (0 lower, 1 upper), ended before, takes `count` member channels (0: none).
    fn start_zone(&mut self, zone: usize, count: u8) {
        let master = 15 * zone;
        self.members[zone] = count;
        if count > 0 {
            self.ranges[master] = Some(MPE_MASTER_RANGE);
            for c in Self::members_of(master, count) {
                self.ranges[c] = Some(MPE_MEMBER_RANGE);
            }
        }
    }

    /// The member channels of the zone mastered by `master` (0 or 15) with `count` members.
    fn members_of(master: usize, count: u8) -> impl Iterator<Item = usize> {
        (1..=usize::from(count)).map(move |i| if master == 0 { i } else { 15 - i })
    }

    /// The channels a controller sent on `channel` speaks for: a configured zone's master channel
    /// speaks for itself and every member of its zone; any other channel for itself.
    pub(crate) fn spoken_for(&self, channel: u8) -> impl Iterator<Item = usize> {
        let c = usize::from(channel & 15);
        let zone = match c {
            0 => Some(0),
            15 => Some(1),
            _ => None,
        };
        let members = zone.map_or(0, |z| self.members[z]);
        std::iter::once(c).chain(Self::members_of(c, members))
    }

    /// Semitones of a full bend on `channel`, if a controller set it.
    pub(crate) fn range(&self, channel: u8) -> Option<f64> {
        self.ranges[usize::from(channel & 15)]
    }

    /// The master channel of the MPE zone `channel` is a member of, if any.
    pub(crate) fn master(&self, channel: u8) -> Option<u8> {
        let (c, [lower, upper]) = (channel & 15, self.members);
        if (1..=lower).contains(&c) {
            Some(0)
        } else if (15 - upper..15).contains(&c) {
            Some(15)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn send(bends: &mut Bends, channel: u8, messages: &[(u8, u8)]) {
        for &(cc, value) in messages {
            bends.controller(channel, cc, value, SETTING);
        }
    }

    /// The `Bend range` setting the tests play with (semitones).
    const SETTING: f64 = 12.0;

    /// Cents sent without semitones refine the channel's own semitones: the setting's on a
    /// channel never told (12.5 with the setting at 12), a controller's once told.
    #[test]
    fn cents_alone_refine_the_channels_semitones() {
        let mut b = Bends::default();
        send(&mut b, 3, &[(101, 0), (100, 0), (38, 50)]);
        assert_eq!(b.range(3), Some(SETTING + 0.5));
        send(&mut b, 4, &[(101, 0), (100, 0), (6, 7), (38, 25), (38, 50)]);
        assert_eq!(b.range(4), Some(7.5));
    }

    #[test]
    fn sensitivity_is_set_in_semitones_and_cents_on_its_channel_only() {
        let mut b = Bends::default();
        send(&mut b, 3, &[(101, 0), (100, 0), (6, 7), (38, 50)]);
        assert_eq!(b.range(3), Some(7.5));
        assert_eq!(b.range(2), None);
        send(&mut b, 3, &[(6, 12)]);
        assert_eq!(b.range(3), Some(12.0), "a new coarse value starts with no cents");
    }

    #[test]
    fn data_without_the_sensitivity_selected_is_ignored() {
        let mut b = Bends::default();
        send(&mut b, 0, &[(6, 24)]);
        assert_eq!(b.range(0), None, "nothing selected at first");
        send(&mut b, 0, &[(101, 0), (100, 1), (6, 24)]);
        assert_eq!(b.range(0), None, "fine tuning is another parameter");
        send(&mut b, 0, &[(100, 0), (101, 127), (100, 127), (6, 24)]);
        assert_eq!(b.range(0), None, "the null parameter takes no data");
        send(&mut b, 0, &[(101, 0), (100, 0)]);
        b.reset_controllers(0);
        send(&mut b, 0, &[(6, 24)]);
        assert_eq!(b.range(0), None, "reset-all-controllers deselects");
    }

    #[test]
    fn reset_all_controllers_keeps_the_sensitivity() {
        let mut b = Bends::default();
        send(&mut b, 5, &[(101, 0), (100, 0), (6, 5)]);
        b.reset_controllers(5);
        assert_eq!(b.range(5), Some(5.0));
    }

    #[test]
    fn an_mpe_configuration_sets_its_zones_ranges_and_members() {
        let mut b = Bends::default();
        send(&mut b, 0, &[(101, 0), (100, 6), (6, 3)]);
        assert_eq!(b.range(0), Some(MPE_MASTER_RANGE));
        assert_eq!((1..=3).map(|c| b.range(c)).collect::<Vec<_>>(), [Some(MPE_MEMBER_RANGE); 3]);
        assert_eq!(b.range(4), None);
        assert_eq!((b.master(2), b.master(4), b.master(0)), (Some(0), None, None));
        send(&mut b, 15, &[(101, 0), (100, 6), (6, 2)]);
        assert_eq!((b.master(14), b.master(13), b.master(12)), (Some(15), Some(15), None));
        assert_eq!(b.range(13), Some(MPE_MEMBER_RANGE));
        // Fewer members: the ones left out follow the setting again; 0 ends the zone.
        send(&mut b, 0, &[(6, 1)]);
        assert_eq!((b.range(1), b.range(2), b.master(2)), (Some(MPE_MEMBER_RANGE), None, None));
        send(&mut b, 0, &[(6, 0)]);
        assert_eq!((b.range(0), b.range(1), b.master(1)), (None, None, None));
        // Only on a master channel.
        send(&mut b, 4, &[(101, 0), (100, 6), (6, 3)]);
        assert_eq!((b.range(5), b.master(5)), (None, None));
    }

    /// The zones never overlap: a lower zone of 10 members over an upper zone of 10 leaves it
    /// the 4 channels left, which it keeps when the lower zone ends; a lower zone of 15 (channels
    /// 2–16) ends the upper zone, its master now a member; ending the upper zone then, which is
    /// not there, changes nothing.
    #[test]
    fn the_zone_configured_last_keeps_its_channels_and_the_other_shrinks() {
        let mut b = Bends::default();
        let zone = |b: &mut Bends, master: u8, members: u8| send(b, master, &[(101, 0), (100, 6), (6, members)]);
        let masters = |b: &Bends| (0..16).map(|c| b.master(c)).collect::<Vec<_>>();
        let layout = |lower: usize, upper: usize| {
            let member = |c: usize, m| if c == 0 || c == 15 { None } else { m };
            (0..16)
                .map(|c| {
                    if c <= lower {
                        member(c, Some(0))
                    } else if c >= 15 - upper {
                        member(c, Some(15))
                    } else {
                        None
                    }
                })
                .collect::<Vec<_>>()
        };
        zone(&mut b, 15, 10);
        zone(&mut b, 0, 10);
        assert_eq!(masters(&b), layout(10, 4));
        assert_eq!((b.range(0), b.range(15), b.range(10), b.range(11)), (Some(2.0), Some(2.0), Some(48.0), Some(48.0)));
        zone(&mut b, 0, 0);
        assert_eq!(masters(&b), layout(0, 4), "the upper zone kept 4 members");
        assert_eq!((b.range(10), b.range(11)), (None, Some(48.0)));
        zone(&mut b, 0, 15);
        let members = |b: &Bends| (1..16).all(|c| b.master(c) == Some(0) && b.range(c) == Some(48.0));
        assert!(members(&b), "channels 2–16 are members of the lower zone");
        zone(&mut b, 15, 0);
        assert!(members(&b), "ending no zone changes nothing");
    }

    /// A zone's master speaks for itself and its members; another channel, or a master without a
    /// zone, for itself alone.
    #[test]
    fn a_zones_master_speaks_for_its_members() {
        let mut b = Bends::default();
        let spoken = |b: &Bends, c: u8| b.spoken_for(c).collect::<Vec<_>>();
        assert_eq!((spoken(&b, 0), spoken(&b, 15), spoken(&b, 3)), (vec![0], vec![15], vec![3]));
        send(&mut b, 0, &[(101, 0), (100, 6), (6, 3)]);
        send(&mut b, 15, &[(101, 0), (100, 6), (6, 2)]);
        assert_eq!((spoken(&b, 0), spoken(&b, 15), spoken(&b, 2)), (vec![0, 1, 2, 3], vec![15, 14, 13], vec![2]));
    }

    /// A sensitivity sent on one member channel of a zone sets every member of that zone (JUCE's
    /// `MPEMessages` sends the per-note range on the first member channel only), and not the
    /// master, the other zone, or a channel outside both.
    #[test]
    fn a_sensitivity_sent_on_one_member_channel_sets_the_whole_zone() {
        let mut b = Bends::default();
        send(&mut b, 0, &[(101, 0), (100, 6), (6, 3)]);
        send(&mut b, 15, &[(101, 0), (100, 6), (6, 2)]);
        send(&mut b, 1, &[(101, 0), (100, 0), (6, 24), (38, 50)]);
        let ranges = |b: &Bends| (0..16).map(|c| b.range(c)).collect::<Vec<_>>();
        let mut want = vec![None; 16];
        want[0] = Some(MPE_MASTER_RANGE);
        want[1..=3].fill(Some(24.5));
        want[15] = Some(MPE_MASTER_RANGE);
        want[13..=14].fill(Some(MPE_MEMBER_RANGE));
        assert_eq!(ranges(&b), want);
        // On a channel outside both zones, that channel alone.
        send(&mut b, 6, &[(101, 0), (100, 0), (6, 7)]);
        want[6] = Some(7.0);
        assert_eq!(ranges(&b), want);
    }

    /// Deselecting every channel's parameter (the instrument's reset) keeps the sensitivities and
    /// the zones: data entry then sets nothing until a parameter is selected again.
    #[test]
    fn deselecting_keeps_the_sensitivities_and_zones() {
        let mut b = Bends::default();
        send(&mut b, 0, &[(101, 0), (100, 6), (6, 3)]);
        send(&mut b, 5, &[(101, 0), (100, 0), (6, 5)]);
        let kept = b.clone();
        b.deselect_all();
        assert_eq!((b.ranges, b.members), (kept.ranges, kept.members));
        send(&mut b, 5, &[(6, 9)]);
        assert_eq!(b.range(5), Some(5.0), "nothing selected");
    }

    /// A non-registered parameter (CC99, CC98) deselects the registered one: its data (a GS
    /// vibrato rate, say) does not set the bend range.
    #[test]
    fn a_non_registered_parameters_data_leaves_the_sensitivity_alone() {
        let mut b = Bends::default();
        send(&mut b, 0, &[(101, 0), (100, 0), (6, 12), (99, 1), (98, 8), (6, 64)]);
        assert_eq!(b.range(0), Some(12.0));
        send(&mut b, 0, &[(101, 0), (100, 0), (6, 7)]);
        assert_eq!(b.range(0), Some(7.0), "selecting it again");
    }
}
