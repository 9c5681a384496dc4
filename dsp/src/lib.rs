//! # qsa-dsp: lumped-collision physics for QSA Strings
//!
//! Real-time simulation of lumped collisions in musical instruments with the non-iterative
//! quadratic spline approximation (QSA) of the contact potential (Bhanuprakash, van Walstijn and
//! Chatziioannou, DAFx-24; "the seed" below), with the iterative (IMP) and explicit (EXP)
//! schemes alongside as references.
//!
//! - [`contact`]: the power law, its spline fit and the three solvers of the common scalar
//!   problem `s + z − q F = 0` (seed eq. 18).
//! - [`string`]: the modal stiff string with exact per-mode coefficients.
//! - [`bridge`]: the bridge and soundboard at the bridge point, a modal bank the strings drive.
//! - [`body`]: the body as a listener hears it, the bridge force radiated through its modes.
//! - [`pickup`]: the magnetic pickup's electrical response.
//! - [`exciter`]: the hammer (and the slide and fingers).
//! - [`scene`]: physical set-ups built from a solver and bodies; each holds only what it needs.
//! - [`instrument`]: the playable engine: a voice pool driven by note and controller events.
//! - [`scene_file`]: scene files (TOML): parsing and validation, the scene vocabulary, the one
//!   builder from a description and a solver choice to a runnable scene, offline rendering in
//!   calls of any size, and what a render measured.
//!
//! **Units** are SI throughout: m, kg, N, s, Hz, J. State and arithmetic are `f64`.
//!
//! A render, from a scene file to frames:
//!
//! ```
//! let text = r#"
//!     scene = "mass-barrier"
//!     sample_rate = 44100
//!     duration = 0.002
//!     solver = { method = "qsa", segments = 5 }
//!     contact = { kappa = 1e8, alpha = 1.3 }
//!     mass = { mass = 0.01, u0 = -1e-3, v0 = 2.0 }
//!     barrier = { position = 0.0 }
//! "#;
//! let scene = qsa_dsp::scene_file::parse_scene(text).unwrap();
//! let out = qsa_dsp::scene_file::render(&scene, std::iter::empty()).unwrap();
//! assert_eq!(out.measurements.contacts, 1);
//! assert!((out.measurements.rebound_velocity.unwrap() + 2.0).abs() < 1e-9);
//! ```

#[doc(hidden)]
pub mod bench_support;
pub mod body;
pub mod bridge;
pub mod contact;
pub mod control;
pub mod exciter;
pub mod instrument;
pub mod pickup;
pub mod preset;
pub mod scene;
pub mod scene_file;
pub mod string;
