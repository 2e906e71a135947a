//! Synthetic demonstrations built from straight and curved moves, for tests and benchmarks.
//!
//! Not the simulated teacher (that one follows a task's teaching steps): this is a small
//! builder that knows exactly where its true lines are, so learned keyframes can be checked
//! against them. It also plays the online detector's part in a simplified, documented way: a
//! line is detected once the hand has moved `2·D_F` along it (three filtered points), and the
//! detection lasts until the hand is `D_F` past its end; an answer "no" switches it off at once.

use crate::demo::{
    Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, ObjectTrack, DEMO_VERSION,
};
use akl_tsr::nalgebra::{Translation3, UnitQuaternion, Vector3};
use akl_tsr::{Gripper, Pose};
use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A true line demonstrated by the builder: frames `start..=end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueLine {
    /// First frame of the line.
    pub start: usize,
    /// Last frame of the line.
    pub end: usize,
    /// The answer given to the detector's query, if any.
    pub answer: Option<Answer>,
}

/// Builds a [`Demo`] move by move.
pub struct DemoBuilder {
    rate: f64,
    noise: f64,
    filter_distance: f64,
    rng: ChaCha8Rng,
    header: DemoHeader,
    exact: Vec<Vector3<f64>>,
    rotation: UnitQuaternion<f64>,
    gripper: Vec<Gripper>,
    objects: Vec<(String, Vec<Pose>)>,
    held: Option<(usize, Pose)>,
    lines: Vec<TrueLine>,
    marks: Vec<usize>,
    state: Gripper,
}

impl DemoBuilder {
    /// A demo of `task` at `rate` frames per second starting with the hand at `start`
    /// pointing down, gripper open; `noise` is the standard deviation (metres) of the
    /// position noise added to every recorded end-effector position; `seed` fixes it.
    pub fn new(task: &str, start: [f64; 3], rate: f64, noise: f64, seed: u64) -> Self {
        DemoBuilder {
            rate,
            noise,
            filter_distance: 0.05,
            rng: ChaCha8Rng::seed_from_u64(seed),
            header: DemoHeader {
                akl_demo: DEMO_VERSION,
                task: task.into(),
                frame: "world".into(),
                calibration: None,
                shapes: Default::default(),
            },
            exact: vec![Vector3::from(start)],
            rotation: UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0),
            gripper: vec![Gripper::Open],
            objects: Vec::new(),
            held: None,
            lines: Vec::new(),
            marks: Vec::new(),
            state: Gripper::Open,
        }
    }

    /// Adds an object resting at `p` (identity orientation).
    pub fn object(mut self, name: &str, p: [f64; 3]) -> Self {
        let pose = Pose::from_parts(
            Translation3::from(Vector3::from(p)),
            UnitQuaternion::identity(),
        );
        let n = self.exact.len();
        self.objects.push((name.into(), vec![pose; n]));
        self
    }

    fn here(&self) -> Vector3<f64> {
        *self.exact.last().unwrap_or(&Vector3::zeros())
    }

    fn push(&mut self, p: Vector3<f64>) {
        self.exact.push(p);
        self.gripper.push(self.state);
        let ee = Pose::from_parts(Translation3::from(p), self.rotation);
        for (i, (_, poses)) in self.objects.iter_mut().enumerate() {
            let next = match self.held {
                Some((h, offset)) if h == i => ee * offset,
                _ => *poses.last().expect("objects have a pose per frame"),
            };
            poses.push(next);
        }
    }

    fn frames_for(&self, length: f64, speed: f64) -> usize {
        ((length / speed) * self.rate).ceil().max(1.0) as usize
    }

    /// Moves along a curve (a quadratic Bézier whose control point stands off the chord's
    /// middle by 0.3 of its length, upwards square to the chord, or sideways for a vertical
    /// chord) to `to` at about `speed` m/s, easing in and out.
    pub fn curve(mut self, to: [f64; 3], speed: f64) -> Self {
        let (a, b) = (self.here(), Vector3::from(to));
        let chord = (b - a).try_normalize(1e-12).unwrap_or_else(Vector3::x);
        let up = (Vector3::z() - chord * chord.z)
            .try_normalize(1e-6)
            .unwrap_or_else(Vector3::x);
        let mid = (a + b) * 0.5 + up * 0.3 * (b - a).norm().max(0.02);
        let n = self.frames_for((b - a).norm() * 1.3, speed);
        for i in 1..=n {
            let s = ease(i as f64 / n as f64);
            let p = a * (1.0 - s) * (1.0 - s) + mid * 2.0 * s * (1.0 - s) + b * s * s;
            self.push(p);
        }
        self
    }

    /// Moves in a straight line to `to` at about `speed` m/s; the detector notices it and the
    /// teacher gives `answer` to the query (none when `None`).
    pub fn line(mut self, to: [f64; 3], speed: f64, answer: Option<Answer>) -> Self {
        let (a, b) = (self.here(), Vector3::from(to));
        let n = self.frames_for((b - a).norm(), speed);
        let start = self.exact.len() - 1;
        for i in 1..=n {
            let s = ease(i as f64 / n as f64);
            self.push(a + (b - a) * s);
        }
        self.lines.push(TrueLine {
            start,
            end: self.exact.len() - 1,
            answer,
        });
        self
    }

    /// Holds still for `seconds`.
    pub fn pause(mut self, seconds: f64) -> Self {
        let p = self.here();
        for _ in 0..(seconds * self.rate).round() as usize {
            self.push(p);
        }
        self
    }

    /// Closes the gripper on the object named `name` (it moves with the hand from now on).
    pub fn grasp(mut self, name: &str) -> Self {
        let ee = Pose::from_parts(Translation3::from(self.here()), self.rotation);
        if let Some(i) = self.objects.iter().position(|(n, _)| n == name) {
            let obj = *self.objects[i].1.last().expect("pose per frame");
            self.held = Some((i, ee.inverse() * obj));
        }
        self.state = Gripper::Closed;
        let p = self.here();
        self.push(p);
        self
    }

    /// Opens the gripper (whatever was held stays where it is).
    pub fn release(mut self) -> Self {
        self.held = None;
        self.state = Gripper::Open;
        let p = self.here();
        self.push(p);
        self
    }

    /// Marks the current pose as a keyframe (keyframe demonstrations).
    pub fn mark(mut self) -> Self {
        self.marks.push(self.exact.len() - 1);
        self
    }

    /// The true lines demonstrated so far.
    pub fn lines(&self) -> &[TrueLine] {
        &self.lines
    }

    /// The exact (noise-free) end-effector position at `frame`.
    pub fn exact(&self, frame: usize) -> Vector3<f64> {
        self.exact[frame]
    }

    /// The demo: noisy end-effector poses, object poses, gripper, detector states and dialogue.
    pub fn build(&mut self) -> Demo {
        let n = self.exact.len();
        let times: Vec<f64> = (0..n).map(|k| k as f64 / self.rate).collect();
        let noise = self.noise;
        let rng = &mut self.rng;
        let ee: Vec<Pose> = self
            .exact
            .iter()
            .map(|p| {
                let d = Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * noise;
                Pose::from_parts(Translation3::from(p + d), self.rotation)
            })
            .collect();
        let mut detector = vec![false; n];
        let mut events = Vec::new();
        for line in &self.lines {
            let Some(on) = self.detected_start(line) else {
                continue;
            };
            let off = self.detected_end(line);
            let off = if line.answer == Some(Answer::No) {
                (on + 1).min(n - 1)
            } else {
                off
            };
            detector[on..=off].iter_mut().for_each(|d| *d = true);
            events.push(DialogueEvent {
                t: times[on],
                frame: on,
                kind: DialogueKind::Query,
            });
            if let Some(a) = line.answer {
                events.push(DialogueEvent {
                    t: times[on],
                    frame: on,
                    kind: DialogueKind::Answer(a),
                });
            }
        }
        for &m in &self.marks {
            events.push(DialogueEvent {
                t: times[m],
                frame: m,
                kind: DialogueKind::Keyframe,
            });
        }
        events.sort_by_key(|e| e.frame);
        Demo {
            header: self.header.clone(),
            times,
            ee,
            gripper: self.gripper.clone(),
            objects: self
                .objects
                .iter()
                .map(|(name, poses)| ObjectTrack {
                    name: name.clone(),
                    poses: poses.clone(),
                })
                .collect(),
            detector,
            events,
        }
    }

    fn detected_start(&self, line: &TrueLine) -> Option<usize> {
        let a = self.exact[line.start];
        (line.start..=line.end).find(|&k| (self.exact[k] - a).norm() >= 2.0 * self.filter_distance)
    }

    fn detected_end(&self, line: &TrueLine) -> usize {
        let b = self.exact[line.end];
        (line.end..self.exact.len())
            .find(|&k| (self.exact[k] - b).norm() >= self.filter_distance)
            .unwrap_or(self.exact.len() - 1)
    }
}

fn ease(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u: f64 = rng.gen_range(f64::EPSILON..1.0);
    let v: f64 = rng.gen_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}
