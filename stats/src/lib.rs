//! The statistics behind AKL's verdicts.
//!
//! A verdict of the simulation is a measurement: a batch of randomized trials says how often a
//! spec passed, with an exact confidence interval ([`PassRate`]), and a deployment decision is
//! made by [`gate`]'s sequential test, whose operating characteristic is computed exactly. The
//! crate knows nothing of robots: trials are Bernoulli outcomes in seed order.

pub mod gate;
mod interval;

pub use gate::{Decision, Gate, GateError, GateOptions, GateVerdict, OperatingPoint};
pub use interval::{percent, PassRate, CONFIDENCE};
