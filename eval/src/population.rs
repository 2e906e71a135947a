//! The simulated participants of the study, fixed before any result was looked at.
//!
//! The thesis's study had 12 participants, 5 of whom had handled robots before (§4.5.1); each
//! calibrated, then taught the three tasks with each of the three methods, the order of the
//! methods balanced by one 3×3 Latin square (§4.4). The population here mirrors that: a share
//! of experienced teachers and a share of first-time ones, each participant's habits drawn
//! uniformly from its group's ranges with a seed, and the method order taken from the Latin
//! square row by row.
//!
//! Every range is set from what the thesis reports about its participants, never from this
//! study's results; each number's reason is beside it in [`Population::study`]. The figures it
//! relies on:
//! - **Unintended lines.** mACL learns a line wherever the hand moved straight for about 10 cm,
//!   so on the pick-and-place task (no line, five free motions) it succeeds only when no free
//!   motion was straight: 33.3 % (Table 4.1) means a chance of about 1 − 0.333^(1/5) ≈ 0.2 per
//!   free motion. AKL's numbers agree: the study's 20 corrected plus about 8 wrongly kept
//!   detections over 36 AKL trials of 4–5 free motions each (Table 4.2) are 0.17 per motion.
//! - **Answers.** Table 4.2: 14 constraint errors came from answers and 20 were avoided by
//!   them. With r the share of answers that keep a wrong state (a wrong "yes" or an "I don't
//!   know" on an unintended line, a wrong "no" on a required one), U detected unintended lines
//!   and the 24 required lines of the line tasks: (1 − r)·U = 20 and r·(U + 24) = 14 give
//!   r ≈ 0.27, U ≈ 27. Split as about 0.17 wrong answers and 0.08 "I don't know".
//! - **Keyframe marks.** KD succeeds on pick and place 50.0 % of the time (Table 4.1): its
//!   gripper commands give the four keyframes, so a trial fails exactly when the teacher marks
//!   a keyframe the task does not need — the end of the return to the start, or one in the
//!   middle of a motion. (1 − f)·(1 − e)⁵ = 0.5 with f ≈ 0.25 for the return and e ≈ 0.07
//!   per step for the middle.
//! - **Suggestions.** The thesis lets the teacher accept or decline a suggestion and does not
//!   report which (§3.3.1.2); uptakes are spread around one half.
//! - **Motion.** Speeds, tremor and curvature span the simulated teacher's careful and
//!   first-time presets (see [`akl_learn::teacher::TeacherProfile`]); experienced teachers
//!   move faster and steadier.

use akl_learn::teacher::{KeyframeHabit, TeacherProfile};
use akl_learn::Method;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The method orders of the study's Latin square (thesis §4.4): participant i takes row
/// i mod 3, so each method is taught first, second and third equally often.
pub(crate) const LATIN_SQUARE: [[Method; 3]; 3] = [
    [Method::Akl, Method::Kd, Method::Macl],
    [Method::Kd, Method::Macl, Method::Akl],
    [Method::Macl, Method::Akl, Method::Kd],
];

/// A closed range a parameter is drawn from uniformly.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Span {
    /// Lowest value.
    pub lo: f64,
    /// Highest value.
    pub hi: f64,
}

const fn span(lo: f64, hi: f64) -> Span {
    Span { lo, hi }
}

impl Span {
    fn draw(&self, rng: &mut ChaCha8Rng) -> f64 {
        if self.hi > self.lo {
            rng.gen_range(self.lo..=self.hi)
        } else {
            self.lo
        }
    }
}

/// The ranges of one group of participants' habits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Group {
    /// Hand speed along the path (m/s).
    pub speed: Span,
    /// Tremor amplitude (m).
    pub tremor: Span,
    /// How far free motion bows off the straight line (sagitta / length).
    pub curvature: Span,
    /// Chance that a free motion is made in a straight line.
    pub unintended_line_chance: Span,
    /// How much one suggestion lowers that chance (fraction).
    pub suggestion_uptake: Span,
    /// Chance that an answer is wrong.
    pub wrong_answer_rate: Span,
    /// Chance that an answer is "I don't know".
    pub unknown_answer_rate: Span,
    /// Chance of forgetting a needed keyframe mark (KD).
    pub miss_chance: Span,
    /// Chance of marking the end of a free move no keyframe is needed at (KD).
    pub free_move_mark: Span,
    /// Extra marks per step in the middle of the motion (KD).
    pub extra_per_step: Span,
    /// Pause at each grasp and release (s).
    pub dwell: Span,
}

/// The study's population: two groups and how they are mixed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Population {
    /// Share of participants who have handled robots before.
    pub experienced_share: f64,
    /// Their habits.
    pub experienced: Group,
    /// The first-time teachers' habits.
    pub first_time: Group,
    /// Relative spread of every teacher's speed from motion to motion (uniform, ±).
    pub speed_variation: f64,
    /// Position sensor noise (m), the robot's, the same for everyone.
    pub sensor_noise: f64,
    /// Recording rate (Hz).
    pub rate: f64,
}

/// One simulated participant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Participant {
    /// 1-based number.
    pub id: usize,
    /// Whether the participant has handled robots before.
    pub experienced: bool,
    /// The participant's habits when the study starts.
    pub profile: TeacherProfile,
    /// The order the participant uses the methods in (a row of the 3×3 Latin square of the methods).
    pub order: [Method; 3],
    /// Seed of everything the participant does.
    pub seed: u64,
}

impl Population {
    /// The population of the study, fixed before any result was seen (see the module docs for
    /// the figures each reason cites).
    pub fn study() -> Population {
        Population {
            // 5 of the thesis's 12 participants had robot experience (§4.5.1).
            experienced_share: 5.0 / 12.0,
            experienced: Group {
                // Kinesthetic teaching of a 7 kg arm is slow; the careful preset moves at
                // 0.12 m/s, someone used to the arm somewhat faster.
                speed: span(0.11, 0.15),
                // About 1 mm of physiological tremor at the hand for a steady hand.
                tremor: span(0.0008, 0.0012),
                // Free reaches bow a quarter of their length (careful preset), a little less
                // for someone who knows a robot does not need it.
                curvature: span(0.2, 0.3),
                // Half the population mean of 0.2 per free motion (module docs): experience
                // with robots makes straight free motion rarer but not absent.
                unintended_line_chance: span(0.05, 0.15),
                // Unmeasured in the thesis: around one half.
                suggestion_uptake: span(0.4, 0.8),
                // Below the population's 0.17: they know what the robot needs.
                wrong_answer_rate: span(0.05, 0.15),
                unknown_answer_rate: span(0.0, 0.08),
                // Forgetting a needed mark is rare and costs KD nothing at gripper commands.
                miss_chance: span(0.0, 0.1),
                // Below the population's f ≈ 0.25.
                free_move_mark: span(0.0, 0.3),
                // Below the population's e ≈ 0.07.
                extra_per_step: span(0.0, 0.08),
                // Half a second to a second at each grasp and release.
                dwell: span(0.5, 0.8),
            },
            first_time: Group {
                // Around the first-time preset's 0.1 m/s.
                speed: span(0.08, 0.12),
                // Up to the first-time preset's 2 mm.
                tremor: span(0.0012, 0.002),
                // Down to 0.15, where the detector starts taking parts of free motion for
                // lines (the calibration survey's lowest curvature).
                curvature: span(0.15, 0.25),
                // With the experienced group's 0.05–0.15, 7 of 12 at 0.15–0.35 make the
                // population mean (5·0.1 + 7·0.25) / 12 ≈ 0.19 per free motion.
                unintended_line_chance: span(0.15, 0.35),
                suggestion_uptake: span(0.25, 0.75),
                // Population means (5·0.1 + 7·0.225) / 12 ≈ 0.17 wrong and
                // (5·0.04 + 7·0.1) / 12 ≈ 0.08 "I don't know" (module docs).
                wrong_answer_rate: span(0.15, 0.3),
                unknown_answer_rate: span(0.05, 0.15),
                miss_chance: span(0.05, 0.2),
                // Population means (5·0.15 + 7·0.325) / 12 ≈ 0.25 for the return and
                // (5·0.04 + 7·0.09) / 12 ≈ 0.07 per step in the middle (module docs).
                free_move_mark: span(0.15, 0.5),
                extra_per_step: span(0.03, 0.15),
                dwell: span(0.6, 1.0),
            },
            // ±25–40 % in the presets; one value for all.
            speed_variation: 0.3,
            // The presets' 0.5 mm: the arm's own sensing, not the teacher's.
            sensor_noise: 0.0005,
            // The presets' recording rate.
            rate: 100.0,
        }
    }

    /// `n` participants drawn with `seed`: round(n · share) of them experienced (which ones is
    /// drawn too), every habit drawn from the participant's group, participant i (0-based)
    /// teaching in the order of Latin-square row i mod 3.
    pub fn draw(&self, n: usize, seed: u64) -> Vec<Participant> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let experienced = (n as f64 * self.experienced_share).round() as usize;
        let mut is_experienced: Vec<bool> = (0..n).map(|i| i < experienced).collect();
        is_experienced.shuffle(&mut rng);
        is_experienced
            .into_iter()
            .enumerate()
            .map(|(i, experienced)| {
                let group = if experienced {
                    &self.experienced
                } else {
                    &self.first_time
                };
                Participant {
                    id: i + 1,
                    experienced,
                    profile: self.profile(group, &mut rng),
                    order: LATIN_SQUARE[i % LATIN_SQUARE.len()],
                    seed: rng.gen(),
                }
            })
            .collect()
    }

    fn profile(&self, g: &Group, rng: &mut ChaCha8Rng) -> TeacherProfile {
        TeacherProfile {
            speed: g.speed.draw(rng),
            speed_variation: self.speed_variation,
            tremor: g.tremor.draw(rng),
            sensor_noise: self.sensor_noise,
            curvature: g.curvature.draw(rng),
            unintended_line_chance: g.unintended_line_chance.draw(rng),
            suggestion_uptake: g.suggestion_uptake.draw(rng),
            wrong_answer_rate: g.wrong_answer_rate.draw(rng),
            unknown_answer_rate: g.unknown_answer_rate.draw(rng),
            keyframes: KeyframeHabit {
                miss_chance: g.miss_chance.draw(rng),
                free_move_mark: g.free_move_mark.draw(rng),
                extra_per_step: g.extra_per_step.draw(rng),
            },
            rate: self.rate,
            dwell: g.dwell.draw(rng),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twelve_participants_mirror_the_thesis() {
        let people = Population::study().draw(12, 0);
        assert_eq!(people.len(), 12);
        assert_eq!(people.iter().filter(|p| p.experienced).count(), 5);
        for m in Method::ALL {
            for position in 0..3 {
                let n = people.iter().filter(|p| p.order[position] == m).count();
                assert_eq!(n, 4, "{m} taught {position}th by {n}");
            }
        }
        for p in &people {
            p.profile.validate().unwrap();
        }
        assert_eq!(people, Population::study().draw(12, 0));
        assert_ne!(people, Population::study().draw(12, 1));
    }

    #[test]
    fn the_population_means_are_the_ones_derived_from_the_thesis() {
        let people = Population::study().draw(1200, 3);
        let mean = |f: &dyn Fn(&TeacherProfile) -> f64| {
            people.iter().map(|p| f(&p.profile)).sum::<f64>() / people.len() as f64
        };
        let near = |x: f64, target: f64, tol: f64| (x - target).abs() <= tol;
        assert!(near(mean(&|p| p.unintended_line_chance), 0.19, 0.01));
        assert!(near(mean(&|p| p.wrong_answer_rate), 0.17, 0.01));
        assert!(near(mean(&|p| p.unknown_answer_rate), 0.08, 0.01));
        assert!(near(mean(&|p| p.keyframes.free_move_mark), 0.25, 0.01));
        assert!(near(mean(&|p| p.keyframes.extra_per_step), 0.07, 0.01));
    }
}
