//! QSA Strings as a standalone application: `qsa-strings-standalone --help` lists the audio and
//! MIDI backends (JACK, ALSA, or `--backend dummy` to just open the editor).

fn main() {
    nice_plug::nice_export_standalone::<qsa_plugin::QsaStrings>();
}
