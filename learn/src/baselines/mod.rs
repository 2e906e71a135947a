//! The two methods AKL is compared with in the thesis (§4.1).
//!
//! - [`kd`]: keyframe demonstrations — the keyframes the teacher marked, plus the gripper
//!   commands; no constraints.
//! - [`macl`]: the articulated-constraint learner of Liu et al. augmented with interaction
//!   keyframes — line fits over the whole trajectory, total variation denoising, a fixed
//!   threshold; constraint and interaction keyframes are never combined.
//!
//! Both ground their keyframes exactly as OKL does (`okl::ground`), so the three
//! methods differ only in which frames they pick and what they say about them.

pub mod kd;
pub mod macl;
