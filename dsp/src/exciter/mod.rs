//! The bodies that excite a string through a contact: the piano hammer (and, with the slide
//! scene, the slide–hand oscillator and the fingers).

mod hammer;

pub use hammer::{Hammer, HammerParams};
