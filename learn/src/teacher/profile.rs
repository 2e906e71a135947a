//! How a simulated teacher behaves: noise, speed, mistakes and habits.

use serde::{Deserialize, Serialize};

/// When a teacher marks keyframes in a keyframe demonstration (KD).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KeyframeHabit {
    /// Chance of forgetting to mark the end of a step the task needs a keyframe at (a grasp,
    /// a release, either end of a line).
    pub miss_chance: f64,
    /// Chance of marking the end of a free move the task needs no keyframe at (such as the
    /// return to the start): a teacher told to mark as few keyframes as needed (thesis §4.1)
    /// who marks it anyway.
    pub free_move_mark: f64,
    /// Extra marks per step in the middle of the motion (a teacher who marks too often).
    pub extra_per_step: f64,
}

/// A seeded simulated teacher's parameters. Numbers are metres, seconds and probabilities.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TeacherProfile {
    /// Mean hand speed along the path (m/s). Kinesthetic teaching of a 7-kg arm is slow:
    /// 0.12 m/s makes a 30 cm reach last about 2.5 s.
    pub speed: f64,
    /// Relative spread of the speed from one motion to the next (uniform, ±).
    pub speed_variation: f64,
    /// Peak amplitude of physiological tremor (m, three sinusoids at 8–12 Hz).
    pub tremor: f64,
    /// Standard deviation of the position sensor's white noise (m).
    pub sensor_noise: f64,
    /// How far a free motion bows away from the straight line (the sagitta of its arc), as a
    /// fraction of its length: 0.25 makes a 40 cm reach bow 10 cm out, an arc of radius 0.625×
    /// its length. Much straighter free motion (0.15) is what the dialogue is for: the detector
    /// takes parts of it for lines.
    pub curvature: f64,
    /// Chance that a free motion is made in an unintended straight line.
    pub unintended_line_chance: f64,
    /// How much a suggestion ("Please do not move in a line unless the robot must move in a
    /// line.") lowers that chance for the rest of the demonstration, as a fraction: 0 ignores
    /// suggestions, 1 never moves straight again unless required. The thesis lets the teacher
    /// accept or decline a suggestion and does not measure which; the presets take half.
    pub suggestion_uptake: f64,
    /// Chance that an answer to "Do I have to move in a straight line there?" is wrong.
    pub wrong_answer_rate: f64,
    /// Chance that an answer is "I don't know" instead.
    pub unknown_answer_rate: f64,
    /// Keyframe-marking habits (KD baseline).
    pub keyframes: KeyframeHabit,
    /// Recording rate (Hz), 100 by default, at most 1000.
    pub rate: f64,
    /// Pause at each grasp and release while the gripper moves (s).
    pub dwell: f64,
}

/// Highest supported recording rate (Hz).
pub(super) const MAX_RATE: f64 = 1000.0;

/// Why a simulated teacher cannot demonstrate: a profile parameter out of range, or a
/// teaching step the world cannot support.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TeacherError {
    /// A parameter that is a probability lies outside [0, 1].
    #[error("{name} = {value} is not a probability")]
    NotProbability {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The speed is not positive or its variation not in [0, 1).
    #[error("speed must be positive and speed_variation in [0, 1)")]
    Speed,
    /// The recording rate is outside (0, MAX_RATE].
    #[error("rate {0} Hz is outside (0, {MAX_RATE}]")]
    Rate(f64),
    /// A tremor, noise, curvature, dwell or keyframe habit is negative or not a number.
    #[error("tremor, sensor_noise, curvature, dwell and keyframes.extra_per_step must be ≥ 0")]
    Negative,
    /// The calibration circle's radius is not positive.
    #[error("circle radius {0} m is not positive")]
    Radius(f64),
    /// A teaching step names an object the world lacks or cannot be followed.
    #[error("teaching.steps[{index}] ({step}): {problem}")]
    Step {
        /// Index of the step.
        index: usize,
        /// The step, described.
        step: String,
        /// What is wrong.
        problem: String,
    },
}

impl From<TeacherError> for String {
    fn from(e: TeacherError) -> String {
        e.to_string()
    }
}

impl TeacherProfile {
    /// The careful teacher: no unintended lines, correct answers, marks every keyframe the task
    /// needs and no other. Noise of a steady hand (1 mm tremor, 0.5 mm sensor noise).
    pub fn careful() -> Self {
        TeacherProfile {
            speed: 0.12,
            speed_variation: 0.25,
            tremor: 0.001,
            sensor_noise: 0.0005,
            curvature: 0.25,
            unintended_line_chance: 0.0,
            suggestion_uptake: 0.5,
            wrong_answer_rate: 0.0,
            unknown_answer_rate: 0.0,
            keyframes: KeyframeHabit {
                miss_chance: 0.0,
                free_move_mark: 0.0,
                extra_per_step: 0.0,
            },
            rate: 100.0,
            dwell: 0.6,
        }
    }

    /// A first-time teacher as in the thesis's study (§4.4): moves straight in free space one
    /// time in four, answers wrongly one time in five and says "I don't know" one time in ten
    /// (the study traced 14 of its 19 constraint errors to answers, so answers must be the
    /// dominant error source), shakes more, and marks keyframes unevenly.
    pub fn novice() -> Self {
        TeacherProfile {
            speed: 0.1,
            speed_variation: 0.4,
            tremor: 0.002,
            sensor_noise: 0.0005,
            curvature: 0.2,
            unintended_line_chance: 0.25,
            suggestion_uptake: 0.5,
            wrong_answer_rate: 0.2,
            unknown_answer_rate: 0.1,
            keyframes: KeyframeHabit {
                miss_chance: 0.15,
                free_move_mark: 0.5,
                extra_per_step: 0.5,
            },
            rate: 100.0,
            dwell: 0.8,
        }
    }

    /// A teacher who always moves straight in free space, whatever it is told (to exercise
    /// the dialogue), otherwise careful.
    pub fn straight() -> Self {
        TeacherProfile {
            unintended_line_chance: 1.0,
            suggestion_uptake: 0.0,
            ..TeacherProfile::careful()
        }
    }

    /// The named presets: `default` (= careful), `careful`, `novice`, `straight`.
    pub fn named(name: &str) -> Option<Self> {
        match name {
            "default" | "careful" => Some(TeacherProfile::careful()),
            "novice" => Some(TeacherProfile::novice()),
            "straight" => Some(TeacherProfile::straight()),
            _ => None,
        }
    }

    /// The preset names, for help and error messages.
    pub const NAMES: [&'static str; 4] = ["default", "careful", "novice", "straight"];

    /// Checks that every parameter is in range.
    pub fn validate(&self) -> Result<(), TeacherError> {
        let probabilities = [
            ("unintended_line_chance", self.unintended_line_chance),
            ("suggestion_uptake", self.suggestion_uptake),
            ("wrong_answer_rate", self.wrong_answer_rate),
            ("unknown_answer_rate", self.unknown_answer_rate),
            ("keyframes.miss_chance", self.keyframes.miss_chance),
            ("keyframes.free_move_mark", self.keyframes.free_move_mark),
        ];
        if let Some(&(name, value)) = probabilities.iter().find(|(_, v)| !(0.0..=1.0).contains(v)) {
            return Err(TeacherError::NotProbability { name, value });
        }
        if self.speed.is_nan() || self.speed <= 0.0 || !(0.0..1.0).contains(&self.speed_variation) {
            return Err(TeacherError::Speed);
        }
        if self.rate.is_nan() || self.rate <= 0.0 || self.rate > MAX_RATE {
            return Err(TeacherError::Rate(self.rate));
        }
        if [
            self.tremor,
            self.sensor_noise,
            self.curvature,
            self.dwell,
            self.keyframes.extra_per_step,
        ]
        .iter()
        .any(|v| !v.is_finite() || *v < 0.0)
        {
            return Err(TeacherError::Negative);
        }
        Ok(())
    }
}
