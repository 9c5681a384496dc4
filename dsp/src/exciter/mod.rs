//! The bodies that excite a string through a contact: the piano hammer, the slide–hand
//! oscillator and the fingers.

pub mod finger;
mod hammer;
mod slide;

pub use finger::FingerParams;
pub use hammer::{Hammer, HammerParams};
pub use slide::{HandExchange, HandMotion, SlideHand, SlideParams};
