//! The simulated teacher: a person guiding the arm through a task's teaching intent.
//!
//! It moves like a hand (minimum-jerk timing, curved free motion, varying speed, tremor and
//! sensor noise), moves in true straight lines where the task needs them, commands the gripper,
//! carries grasped objects, and — per its [`TeacherProfile`] — sometimes moves straight without
//! needing to, answers queries wrongly, and marks keyframes with its own habits (for KD).

mod calibration_moves;
mod motion;
mod profile;
mod simulate;

pub use calibration_moves::{calibration_demos, calibration_demos_with};
pub use motion::Noise;
pub use profile::{KeyframeHabit, TeacherError, TeacherProfile};
pub use simulate::{demonstrate, SimulatedDemo, SimulatedTeacher};
