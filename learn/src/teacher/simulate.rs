//! Turning a task's teaching intent into a recorded demonstration.

use akl_scene::{Task, TeachStep, World};
use akl_tsr::{Gripper, Pose, WORLD_FRAME};
use k::nalgebra::{Translation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::motion::{min_jerk, Noise};
use super::profile::{TeacherError, TeacherProfile};
use crate::demo::{Demo, DemoHeader, DialogueEvent, DialogueKind};

/// Fastest hand rotation the simulated teacher makes (rad/s).
const ROTATION_SPEED: f64 = 0.8;
/// Shortest duration of any motion (s).
const MIN_DURATION: f64 = 0.3;

/// A simulated demonstration plus what only the simulation knows.
#[derive(Debug, Clone)]
pub struct SimulatedDemo {
    /// The recording (frames only: the detector and dialogue run on it afterwards or online).
    pub demo: Demo,
    /// Per frame: whether the teacher is deliberately moving in a line the task requires.
    pub intended_line: Vec<bool>,
    /// Per frame: whether the teacher is moving in a straight line the task does not require.
    pub unintended_line: Vec<bool>,
    /// Frames the teacher marks as keyframes (KD baseline), in order.
    pub marked_keyframes: Vec<usize>,
}

impl SimulatedDemo {
    /// Whether the teacher, asked at `frame`, knows it was moving in a required line: the line
    /// is under way or ended within the last `window` frames (the detector answers late).
    pub fn line_required_near(&self, frame: usize, window: usize) -> bool {
        let from = frame.saturating_sub(window);
        self.intended_line[from..=frame.min(self.intended_line.len() - 1)]
            .iter()
            .any(|x| *x)
    }

    /// The recording with the teacher's keyframe marks as dialogue events, as a keyframe
    /// demonstration (KD) records it: no detector ran, no question was asked.
    pub fn with_marks(&self) -> Demo {
        let mut demo = self.demo.clone();
        demo.events = self
            .marked_keyframes
            .iter()
            .map(|&frame| DialogueEvent {
                t: demo.times[frame],
                frame,
                kind: DialogueKind::Keyframe,
            })
            .collect();
        demo
    }
}

/// How a motion gets from one pose to the next.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Path {
    Curved,
    Straight { intended: bool },
}

struct Recorder<'a> {
    profile: &'a TeacherProfile,
    /// The chance of an unintended line now: the profile's, lowered by suggestions heeded.
    unintended_chance: f64,
    rng: ChaCha8Rng,
    noise: Noise,
    t: f64,
    pose: Pose,
    gripper: Gripper,
    objects: Vec<(String, Pose)>,
    held: Option<(usize, Pose)>,
    out: SimulatedDemo,
}

/// Demonstrates `task` in `world` (normally the task's own world) as a teacher with `profile`;
/// `seed` fixes every random choice. The error names a teaching step the world cannot support.
///
/// The whole demonstration is made without a learner listening, so no suggestion reaches the
/// teacher; [`SimulatedTeacher`] demonstrates step by step for a live session.
pub fn demonstrate(
    task: &Task,
    world: &World,
    profile: &TeacherProfile,
    seed: u64,
) -> Result<SimulatedDemo, TeacherError> {
    let mut teacher = SimulatedTeacher::new(task, world, profile, seed)?;
    while teacher.next_step()? {}
    Ok(teacher.finish())
}

/// A simulated teacher demonstrating a task one teaching step at a time, so that a learner
/// can talk to it in between: after a suggestion it moves straight less often.
pub struct SimulatedTeacher<'a> {
    task: &'a Task,
    recorder: Recorder<'a>,
    next: usize,
}

impl<'a> SimulatedTeacher<'a> {
    /// A teacher with `profile` at the task's start pose in `world`, having recorded its first
    /// frames (the start and half a dwell).
    pub fn new(
        task: &'a Task,
        world: &World,
        profile: &'a TeacherProfile,
        seed: u64,
    ) -> Result<Self, TeacherError> {
        profile.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Noise::new(profile.tremor, profile.sensor_noise, &mut rng);
        let objects: Vec<(String, Pose)> = world
            .objects
            .iter()
            .map(|o| (o.name.clone(), o.pose))
            .collect();
        let mut recorder = Recorder {
            profile,
            unintended_chance: profile.unintended_line_chance,
            rng,
            noise,
            t: 0.0,
            pose: task.teaching.start,
            gripper: Gripper::Open,
            objects: objects.clone(),
            held: None,
            out: SimulatedDemo {
                demo: Demo::empty(
                    DemoHeader::new(task.name.clone()),
                    &objects.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(),
                ),
                intended_line: Vec::new(),
                unintended_line: Vec::new(),
                marked_keyframes: Vec::new(),
            },
        };
        recorder.record(false, false);
        recorder.dwell(profile.dwell / 2.0);
        Ok(SimulatedTeacher {
            task,
            recorder,
            next: 0,
        })
    }

    /// Records the next teaching step (after the last one, the closing dwell); false once
    /// everything is recorded. The error names a step the world cannot support.
    pub fn next_step(&mut self) -> Result<bool, TeacherError> {
        let steps = &self.task.teaching.steps;
        let profile = self.recorder.profile;
        let Some(step) = steps.get(self.next) else {
            if self.next == steps.len() {
                self.recorder.dwell(profile.dwell / 2.0);
                self.next += 1;
                return Ok(true);
            }
            return Ok(false);
        };
        let i = self.next;
        self.next += 1;
        let recorder = &mut self.recorder;
        let at = |problem: String| TeacherError::Step {
            index: i,
            step: step.describe(),
            problem,
        };
        let target = recorder.target(step).map_err(at)?;
        let path = match step {
            TeachStep::Line { .. } => Path::Straight { intended: true },
            _ if recorder.rng.gen_bool(recorder.unintended_chance) => {
                Path::Straight { intended: false }
            }
            _ => Path::Curved,
        };
        let first_frame = recorder.out.demo.len();
        recorder.travel(target, path);
        let needed = match step {
            TeachStep::Move { .. } => {
                matches!(steps.get(i + 1), Some(TeachStep::Line { .. }))
            }
            _ => true,
        };
        recorder.mark_keyframes(first_frame, needed);
        match step {
            TeachStep::Grasp { object, tcp } => {
                let index = recorder.object_index(object).map_err(at)?;
                recorder.dwell(profile.dwell / 2.0);
                recorder.gripper = Gripper::Closed;
                recorder.held = Some((index, tcp.inverse()));
                recorder.dwell(profile.dwell / 2.0);
            }
            TeachStep::Release { .. } => {
                recorder.dwell(profile.dwell / 2.0);
                recorder.gripper = Gripper::Open;
                recorder.held = None;
                recorder.dwell(profile.dwell / 2.0);
            }
            TeachStep::Move { .. } | TeachStep::Line { .. } => {}
        }
        Ok(true)
    }

    /// The learner suggested not moving in a line unless required: the teacher takes it to
    /// heart as its profile says, lowering its chance of an unintended line by the fraction
    /// [`TeacherProfile::suggestion_uptake`] for the rest of the demonstration.
    pub fn heed_suggestion(&mut self) {
        self.recorder.unintended_chance *= 1.0 - self.recorder.profile.suggestion_uptake;
    }

    /// The chance that the next free motion is an unintended line.
    pub fn unintended_line_chance(&self) -> f64 {
        self.recorder.unintended_chance
    }

    /// What has been recorded so far.
    pub fn recorded(&self) -> &SimulatedDemo {
        &self.recorder.out
    }

    /// The whole recording.
    pub fn finish(self) -> SimulatedDemo {
        self.recorder.out
    }
}

/// A circular arc from one point to another, bowing out by its sagitta: a hand's free reach
/// curves about evenly along its length.
struct Arc {
    centre: Vector3<f64>,
    radius: f64,
    chord: Vector3<f64>,
    bow: Vector3<f64>,
    half_angle: f64,
}

impl Arc {
    /// The arc from `p0` to `p1` bulging `sagitta` metres towards `bow` (any vector not along
    /// the chord); `None` when it degenerates to the chord.
    fn new(p0: Vector3<f64>, p1: Vector3<f64>, bow: Vector3<f64>, sagitta: f64) -> Option<Arc> {
        let length = (p1 - p0).norm();
        let chord = (p1 - p0) / length;
        let bow = (bow - chord * bow.dot(&chord)).try_normalize(1e-9)?;
        let h = sagitta.clamp(1e-6, length / 2.0);
        let radius = (length * length / 4.0 + h * h) / (2.0 * h);
        Some(Arc {
            centre: (p0 + p1) / 2.0 - bow * (radius - h),
            radius,
            chord,
            bow,
            half_angle: (length / (2.0 * radius)).clamp(-1.0, 1.0).asin(),
        })
    }

    /// The point a fraction `s` ∈ [0, 1] of the way along the arc.
    fn at(&self, s: f64) -> Vector3<f64> {
        let phi = self.half_angle * (2.0 * s - 1.0);
        self.centre + (self.chord * phi.sin() + self.bow * phi.cos()) * self.radius
    }
}

impl Recorder<'_> {
    fn object_index(&self, name: &str) -> Result<usize, String> {
        self.objects
            .iter()
            .position(|(n, _)| n == name)
            .ok_or_else(|| format!("unknown object `{name}`"))
    }

    fn frame_of(&self, name: &str) -> Result<Pose, String> {
        if name == WORLD_FRAME {
            return Ok(Pose::identity());
        }
        Ok(self.objects[self.object_index(name)?].1)
    }

    /// The TCP pose at the end of `step`, with the objects where they are now.
    fn target(&self, step: &TeachStep) -> Result<Pose, String> {
        match step {
            TeachStep::Grasp { object, tcp } => Ok(self.frame_of(object)? * tcp),
            TeachStep::Release { on, place } => {
                let (_, grasp_inverse) = self.held.ok_or("releases while holding nothing")?;
                Ok(self.frame_of(on)? * place * grasp_inverse.inverse())
            }
            TeachStep::Move { to, relative_to } | TeachStep::Line { to, relative_to } => {
                Ok(self.frame_of(relative_to)? * to)
            }
        }
    }

    /// Moves the hand from its current pose to `target` along `path` with minimum-jerk timing.
    fn travel(&mut self, target: Pose, path: Path) {
        let start = self.pose;
        let p0 = start.translation.vector;
        let p1 = target.translation.vector;
        let length = (p1 - p0).norm();
        let angle = start.rotation.angle_to(&target.rotation);
        let speed = self.profile.speed
            * (1.0 + self.profile.speed_variation * self.rng.gen_range(-1.0..=1.0));
        let duration = (length / speed)
            .max(angle / ROTATION_SPEED)
            .max(MIN_DURATION);
        let arc = match path {
            Path::Curved if length > 1e-6 => {
                let direction = (p1 - p0) / length;
                let up = Vector3::z() - direction * direction.z;
                let side = direction.cross(&Vector3::z());
                let bow = up.try_normalize(1e-9).unwrap_or(side) * 0.8
                    + side.try_normalize(1e-9).unwrap_or(up) * self.rng.gen_range(-0.6..0.6);
                let sagitta = self.profile.curvature * length * self.rng.gen_range(0.8..1.2);
                Arc::new(p0, p1, bow, sagitta)
            }
            _ => None,
        };
        let (intended, unintended) = match path {
            Path::Straight { intended } => (intended, !intended && length > 1e-6),
            Path::Curved => (false, false),
        };
        let dt = 1.0 / self.profile.rate;
        let steps = (duration / dt).ceil() as usize;
        for k in 1..=steps {
            let s = min_jerk(k as f64 / steps as f64);
            let position = match &arc {
                Some(arc) => arc.at(s),
                None => p0 + (p1 - p0) * s,
            };
            let rotation = start.rotation.slerp(&target.rotation, s);
            self.pose = Pose::from_parts(Translation3::from(position), rotation);
            self.t += dt;
            self.record(intended, unintended);
        }
        self.pose = target;
    }

    /// Holds still (with tremor) for `seconds`.
    fn dwell(&mut self, seconds: f64) {
        let dt = 1.0 / self.profile.rate;
        for _ in 0..(seconds / dt).round() as usize {
            self.t += dt;
            self.record(false, false);
        }
    }

    /// Records one frame at the current time: noisy hand, exact objects.
    fn record(&mut self, intended: bool, unintended: bool) {
        if let Some((index, grasp_inverse)) = self.held {
            self.objects[index].1 = self.pose * grasp_inverse;
        }
        let noise = self.noise.sample(self.t, &mut self.rng);
        let measured = Pose::from_parts(
            Translation3::from(self.pose.translation.vector + noise),
            self.pose.rotation,
        );
        let demo = &mut self.out.demo;
        demo.times.push(self.t);
        demo.ee.push(measured);
        demo.gripper.push(self.gripper);
        for (track, (_, pose)) in demo.objects.iter_mut().zip(&self.objects) {
            track.poses.push(*pose);
        }
        self.out.intended_line.push(intended);
        self.out.unintended_line.push(unintended);
    }

    /// Marks the end of the motion just made, and extra frames inside it, per the habit: the
    /// end of a step the task needs a keyframe at (`needed`: a grasp, a release, a line's
    /// ends) unless forgotten, the end of any other free move by habit.
    fn mark_keyframes(&mut self, first_frame: usize, needed: bool) {
        let last = self.out.demo.len() - 1;
        let habit = self.profile.keyframes;
        let whole = habit.extra_per_step.floor() as usize;
        let extra = whole + usize::from(self.rng.gen_bool(habit.extra_per_step.fract()));
        let mut marks: Vec<usize> = (0..extra)
            .filter(|_| last > first_frame + 2)
            .map(|_| self.rng.gen_range(first_frame + 1..last))
            .collect();
        let marked = if needed {
            !self.rng.gen_bool(habit.miss_chance)
        } else {
            self.rng.gen_bool(habit.free_move_mark)
        };
        if marked {
            marks.push(last);
        }
        marks.sort_unstable();
        self.out.marked_keyframes.extend(marks);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;

    #[test]
    fn every_builtin_task_is_demonstrated_with_its_gripper_changes() {
        for name in builtin::names() {
            let task = builtin::resolve(name).unwrap();
            let sim = demonstrate(&task, &task.world, &TeacherProfile::careful(), 3).unwrap();
            let demo = &sim.demo;
            let changes = demo.gripper.windows(2).filter(|w| w[0] != w[1]).count();
            let expected = task
                .teaching
                .steps
                .iter()
                .filter(|s| matches!(s, TeachStep::Grasp { .. } | TeachStep::Release { .. }))
                .count();
            assert_eq!(changes, expected, "{name}");
            assert!(demo.times.windows(2).all(|w| w[1] > w[0]));
            let has_line = task
                .teaching
                .steps
                .iter()
                .any(|s| matches!(s, TeachStep::Line { .. }));
            assert_eq!(sim.intended_line.iter().any(|x| *x), has_line, "{name}");
            assert!(sim.unintended_line.iter().all(|x| !x));
        }
    }

    #[test]
    fn the_held_object_follows_the_hand_and_stays_where_released() {
        let task = builtin::resolve("inspection").unwrap();
        let sim = demonstrate(&task, &task.world, &TeacherProfile::careful(), 1).unwrap();
        let demo = &sim.demo;
        let part = demo.objects.iter().find(|o| o.name == "part").unwrap();
        let shelf = task.world.object("shelf_2").unwrap();
        let last = *part.poses.last().unwrap();
        let offset = last.translation.vector - shelf.pose.translation.vector;
        assert!(
            offset.xy().norm() < 0.01,
            "the part ends on shelf_2 ({offset})"
        );
        let first = part.poses[0];
        assert!(
            (first.translation.vector - task.world.object("part").unwrap().pose.translation.vector)
                .norm()
                < 1e-12
        );
    }

    #[test]
    fn the_noise_stays_within_a_few_millimetres() {
        let task = builtin::resolve("pick_place").unwrap();
        let profile = TeacherProfile {
            sensor_noise: 0.0,
            ..TeacherProfile::careful()
        };
        let noisy = demonstrate(&task, &task.world, &profile, 5).unwrap();
        let calm = demonstrate(
            &task,
            &task.world,
            &TeacherProfile {
                tremor: 0.0,
                ..profile
            },
            5,
        )
        .unwrap();
        let worst = noisy
            .demo
            .ee
            .iter()
            .zip(&calm.demo.ee)
            .map(|(a, b)| (a.translation.vector - b.translation.vector).norm())
            .fold(0.0, f64::max);
        assert!(
            worst > 0.0002 && worst <= profile.tremor + 1e-9,
            "worst {worst}"
        );
    }

    #[test]
    fn a_straight_teacher_moves_straight_and_a_seed_repeats() {
        let task = builtin::resolve("pick_place").unwrap();
        let a = demonstrate(&task, &task.world, &TeacherProfile::straight(), 9).unwrap();
        assert!(a.unintended_line.iter().any(|x| *x));
        let b = demonstrate(&task, &task.world, &TeacherProfile::straight(), 9).unwrap();
        assert_eq!(a.demo, b.demo);
    }
}
