//! mACL: the articulated-constraint learner of Liu et al. used as a baseline in the thesis
//! (§4.1), augmented with interaction keyframes at the gripper commands.
//!
//! The thesis fixes the sliding window (5 cm, equal to D_F), the TVD weight (λ = 0.6) and the
//! threshold (2.01), and says that every window gets a least-squares line fit whose fitting
//! error is computed for *all* frames of the trajectory — hence its quadratic cost, which is
//! kept here on purpose. What it leaves open, and the reading chosen:
//!
//! - **Windows.** A window starts at every frame where the hand has moved
//!   [`MaclParams::stride`] (1 cm) from the previous window's start, and spans the frames until
//!   the hand is [`MaclParams::window`] (5 cm) from that start. Distances, not path lengths:
//!   a hand's tremor inflates path length while it holds still.
//! - **Signal.** For each window, the line through it and the fitting error of every frame.
//!   The inliers of the window are the contiguous frames around it whose error is within
//!   [`MaclParams::inlier_tolerance`]; their extent along the line divided by the window length
//!   is the window's *inlier ratio* (how many windows' worth of straight motion the line
//!   explains). A frame's signal is the largest ratio of any window whose inliers contain it.
//!   The threshold 2.01 then reads naturally: a constraint is straight motion that one line
//!   explains over more than two windows (10 cm).
//! - **Segmentation.** The signal is denoised by TVD (λ = 0.6, in window-ratio × frames) and
//!   every maximal run of frames above the threshold is a constraint segment; its first and
//!   last frames are the constraint keyframes. The whole trajectory is processed at once,
//!   ignoring the gripper segments, and constraint keyframes are never combined with the
//!   interaction keyframes, even where they coincide.
//! - **Inlier tolerance** (not given): 2 mm, chosen by measurement with
//!   `cargo test --release -p akl-learn macl_tolerance_survey -- --ignored --nocapture`, which
//!   counts how many of the default simulated teacher's demos of the three built-in tasks
//!   (10 seeds each) get exactly their required lines: 1.0 mm 10/30 (tremor breaks every
//!   line), 1.25 mm 14/30, 1.5 mm 28/30, 1.75 mm 30/30, **2 mm 30/30**, 3 mm 10/30 (parts of
//!   curved free motion pass for 10 cm lines). The baseline is thus tuned to its best on the
//!   default teacher, as the thesis tuned its threshold on labelled demonstrations.

use crate::demo::Demo;
use crate::okl::keyframes::{interaction_keyframes, RawKeyframe};
use crate::okl::line::{fit_line, Line};
use crate::okl::segment::runs;
use crate::okl::{check_demo, ground, task_name, LearnError};
use crate::tvd;
use akl_scene::World;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Bounds, Constraint, KeyframeKind, TaskSpec};

/// Tuning of mACL; the defaults are the thesis's values where it gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaclParams {
    /// Length of the sliding window (m): 0.05, equal to D_F (thesis §4.1).
    pub window: f64,
    /// How far the hand moves between window starts (m): 0.01.
    pub stride: f64,
    /// Largest fitting error (m) of a frame that a window's line still explains: 0.002.
    pub inlier_tolerance: f64,
    /// λ of the TVD of the inlier-ratio signal: 0.6 (thesis §4.1, after Liu et al.).
    pub tvd_lambda: f64,
    /// Threshold on the denoised signal: 2.01 (thesis §4.1).
    pub threshold: f64,
    /// Bounds of every TSR: the same defaults as OKL's.
    pub bounds: Bounds,
}

impl Default for MaclParams {
    fn default() -> Self {
        MaclParams {
            window: 0.05,
            stride: 0.01,
            inlier_tolerance: 0.002,
            tvd_lambda: 0.6,
            threshold: 2.01,
            bounds: crate::okl::OklParams::default().bounds,
        }
    }
}

/// The frames `[start, end)` of each sliding window.
pub(crate) fn windows(positions: &[Vector3<f64>], window: f64, stride: f64) -> Vec<(usize, usize)> {
    let n = positions.len();
    let mut out = Vec::new();
    let mut start = 0;
    while start < n {
        let origin = positions[start];
        let Some(end) = (start..n).find(|&k| (positions[k] - origin).norm() >= window) else {
            break;
        };
        out.push((start, end + 1));
        match (start..n).find(|&k| (positions[k] - origin).norm() >= stride) {
            Some(next) => start = next,
            None => break,
        }
    }
    out
}

/// The inlier ratio of every frame: the longest straight stretch (in windows) that a window's
/// line explains and that contains the frame; 0 where no window's line does.
pub(crate) fn inlier_ratios(positions: &[Vector3<f64>], params: &MaclParams) -> Vec<f64> {
    let mut ratio = vec![0.0; positions.len()];
    let mut errors = vec![0.0; positions.len()];
    for (start, end) in windows(positions, params.window, params.stride) {
        let Some(line) = fit_line(&positions[start..end]) else {
            continue;
        };
        for (e, p) in errors.iter_mut().zip(positions) {
            *e = line.distance(p);
        }
        let Some((a, b)) = inlier_run(&errors, start, end, params.inlier_tolerance) else {
            continue;
        };
        let r = extent(&line, &positions[a..=b]) / params.window;
        for x in &mut ratio[a..=b] {
            *x = f64::max(*x, r);
        }
    }
    ratio
}

/// The maximal run of frames with error within `tolerance` that covers the window's middle
/// frame, or `None` when even that frame is off the line.
fn inlier_run(errors: &[f64], start: usize, end: usize, tolerance: f64) -> Option<(usize, usize)> {
    let middle = (start + end - 1) / 2;
    if errors[middle] > tolerance {
        return None;
    }
    let mut a = middle;
    while a > 0 && errors[a - 1] <= tolerance {
        a -= 1;
    }
    let mut b = middle;
    while b + 1 < errors.len() && errors[b + 1] <= tolerance {
        b += 1;
    }
    Some((a, b))
}

/// How far `points` reach along `line` (max − min of their projections).
fn extent(line: &Line, points: &[Vector3<f64>]) -> f64 {
    let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        let s = (p - line.point).dot(&line.direction);
        (lo.min(s), hi.max(s))
    });
    (hi - lo).max(0.0)
}

/// The constraint segments: maximal runs of frames whose denoised inlier ratio exceeds the
/// threshold, as `(first, last)` frames (runs of one frame are dropped).
pub(crate) fn constraint_segments(
    positions: &[Vector3<f64>],
    params: &MaclParams,
) -> Vec<(usize, usize)> {
    let smoothed = tvd::denoise(&inlier_ratios(positions, params), params.tvd_lambda);
    let above: Vec<bool> = smoothed.iter().map(|s| *s > params.threshold).collect();
    runs(&above)
        .into_iter()
        .map(|r| (*r.start(), *r.end()))
        .filter(|(a, b)| b > a)
        .collect()
}

/// Learns a spec with mACL: constraint keyframes at the boundaries of every constraint
/// segment, interaction keyframes at the gripper commands, never combined.
pub fn learn_macl(
    demo: &Demo,
    world: Option<&World>,
    params: &MaclParams,
) -> Result<TaskSpec, LearnError> {
    let positions = check_demo(demo)?;
    let mut keyframes = interaction_keyframes(&demo.gripper);
    for (a, b) in constraint_segments(&positions, params) {
        for (frame, constraint) in [(a, Constraint::None), (b, Constraint::MoveInLine)] {
            keyframes.push(RawKeyframe {
                frame,
                kind: KeyframeKind::Constraint,
                gripper: demo.gripper[frame],
                constraint,
            });
        }
    }
    // A stable sort keeps an interaction before a constraint keyframe on the same frame.
    keyframes.sort_by_key(|k| k.frame);
    let grounded = ground(&keyframes, demo, world, params.bounds)?;
    Ok(TaskSpec::new(task_name(demo), "macl", grounded))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::okl::synth::DemoBuilder;

    #[test]
    fn windows_advance_by_the_stride_and_span_the_window() {
        let step = 2f64.powi(-10);
        let p: Vec<_> = (0..=100)
            .map(|i| Vector3::new(i as f64 * step, 0.0, 0.0))
            .collect();
        let w = windows(&p, 50.0 * step, 10.0 * step);
        assert_eq!(w.first(), Some(&(0, 51)));
        assert_eq!(w[1], (10, 61));
        assert_eq!(w.last(), Some(&(50, 101)));
        assert!(windows(&p[..20], 50.0 * step, 10.0 * step).is_empty());
    }

    #[test]
    fn a_long_line_between_curves_is_one_constraint_segment() {
        let mut b = DemoBuilder::new("t", [0.3, 0.3, 0.4], 100.0, 0.0005, 3)
            .curve([0.5, 0.2, 0.3], 0.2)
            .line([0.5, -0.1, 0.3], 0.15, None)
            .curve([0.3, -0.3, 0.4], 0.2);
        let demo = b.build();
        let positions: Vec<_> = demo.ee.iter().map(|p| p.translation.vector).collect();
        let segments = constraint_segments(&positions, &MaclParams::default());
        assert_eq!(segments.len(), 1, "{segments:?}");
        let (a, z) = segments[0];
        let line = b.lines()[0];
        assert!((b.exact(a) - b.exact(line.start)).norm() < 0.03);
        assert!((b.exact(z) - b.exact(line.end)).norm() < 0.03);
    }

    /// The measurement behind [`MaclParams::inlier_tolerance`]: for each candidate tolerance,
    /// how many constraint segments mACL finds on the default simulated teacher's demos of the
    /// three built-in tasks (10 seeds each), against the number of required lines.
    #[test]
    #[ignore = "a survey: run with --ignored --nocapture"]
    fn macl_tolerance_survey() {
        use crate::teacher::{demonstrate, TeacherProfile};
        use akl_scene::builtin;
        for tolerance in [0.001, 0.00125, 0.0015, 0.00175, 0.002, 0.003] {
            let params = MaclParams {
                inlier_tolerance: tolerance,
                ..MaclParams::default()
            };
            let mut exact = 0;
            let mut report = Vec::new();
            for name in builtin::names() {
                let task = builtin::resolve(name).unwrap();
                let mut counts = Vec::new();
                for seed in 0..10 {
                    let sim =
                        demonstrate(&task, &task.world, &TeacherProfile::careful(), seed).unwrap();
                    let positions: Vec<_> =
                        sim.demo.ee.iter().map(|p| p.translation.vector).collect();
                    let found = constraint_segments(&positions, &params).len();
                    let wanted = runs(&sim.intended_line).len();
                    exact += usize::from(found == wanted);
                    counts.push(found);
                }
                report.push(format!("{name} {counts:?}"));
            }
            println!(
                "tolerance {:.1} mm: {exact}/30 exact; {}",
                tolerance * 1e3,
                report.join("; ")
            );
        }
    }
}
