//! The study's figures as SVG, drawn with plotters: per method, the distribution over trials
//! of missed plus incorrect keyframes (thesis Figure 4-2b), poses (Figure 4-4b) and constraint
//! length (Figure 4-6a), and the learning runtime on a log scale (Figure 4-9). Each is a box
//! plot per method (median, quartiles, whiskers to the smallest and largest value) over the
//! trials drawn as points, spread sideways so that equal values stay visible, coloured by
//! task. The boxes are drawn from plotters' rectangles and paths rather than its `Boxplot`,
//! whose whiskers end at Tukey's fences: for counts those reach below zero and past the data.

use akl_learn::Method;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

use crate::study::Trial;
use crate::summary::TABLE_ORDER;

/// A figure could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("drawing {figure}: {message}")]
pub struct PlotError {
    /// The figure's file name.
    pub figure: String,
    /// What the plotting library said.
    pub message: String,
}

/// Colours of the tasks' points, in study order.
const TASK_COLOURS: [RGBColor; 3] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
];

/// Smallest runtime drawn on the log axis (s): a measured time of 0 would have no place on it.
const LOG_FLOOR: f64 = 1e-7;

/// One figure: its file name, title, axis label and the value of a trial.
pub(crate) struct Figure {
    /// File name, e.g. `keyframes.svg`.
    pub file: &'static str,
    /// Title.
    pub title: &'static str,
    /// Label of the value axis.
    pub axis: &'static str,
    /// The value of one trial.
    pub value: fn(&Trial) -> f64,
    /// Whether the value axis is logarithmic.
    pub log: bool,
}

/// The four figures of the study.
pub(crate) const FIGURES: [Figure; 4] = [
    Figure {
        file: "keyframes.svg",
        title: "Missed + incorrect keyframes per trial (cf. thesis Fig. 4-2b)",
        axis: "keyframes",
        value: |t| (t.missed_keyframes + t.incorrect_keyframes) as f64,
        log: false,
    },
    Figure {
        file: "poses.svg",
        title: "Missed + incorrect poses per trial (cf. thesis Fig. 4-4b)",
        axis: "poses",
        value: |t| (t.missed_poses + t.incorrect_poses) as f64,
        log: false,
    },
    Figure {
        file: "constraint_length.svg",
        title: "Missed + incorrect constraint length per trial (cf. thesis Fig. 4-6a)",
        axis: "length (cm)",
        value: |t| 100.0 * (t.missed_line_length + t.incorrect_line_length),
        log: false,
    },
    Figure {
        file: "runtime.svg",
        title: "Learning runtime per trial (cf. thesis Fig. 4-9)",
        axis: "runtime (s, log scale)",
        value: |t| t.runtime_s.max(LOG_FLOOR),
        log: true,
    },
];

/// Draws `figure` over `trials` (tasks coloured in the order of `tasks`) as an SVG document.
pub(crate) fn draw(
    figure: &Figure,
    trials: &[Trial],
    tasks: &[String],
) -> Result<String, PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError {
        figure: figure.file.into(),
        message: e.to_string(),
    };
    let points: Vec<(usize, usize, f64)> = trials
        .iter()
        .filter_map(|t| {
            let m = TABLE_ORDER.iter().position(|m| *m == t.method)?;
            let k = tasks.iter().position(|n| *n == t.task).unwrap_or(0);
            Some((m, k, (figure.value)(t)))
        })
        .collect();
    let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
        (lo.min(p.2), hi.max(p.2))
    });
    let (lo, hi) = if points.is_empty() {
        (0.0, 1.0)
    } else {
        (lo, hi)
    };
    let mut svg = String::new();
    if figure.log {
        let range = (lo * 0.5) as f32..(hi * 2.0) as f32;
        plot(&mut svg, figure, &points, tasks, range.log_scale()).map_err(|e| fail(&e))?;
    } else {
        let range = 0f32..((hi.max(lo) * 1.1).max(1.0)) as f32;
        plot(&mut svg, figure, &points, tasks, range).map_err(|e| fail(&e))?;
    }
    Ok(svg)
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn plot<Y>(
    svg: &mut String,
    figure: &Figure,
    points: &[(usize, usize, f64)],
    tasks: &[String],
    y: Y,
) -> DrawResult
where
    Y: AsRangedCoord<Value = f32>,
    Y::CoordDescType: ValueFormatter<f32>,
{
    let root = SVGBackend::with_string(svg, (720, 480)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(figure.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d(0.5f32..3.5f32, y)?;
    let label = |x: &f32| {
        let i = x.round() as usize;
        match (
            i.checked_sub(1).and_then(|i| TABLE_ORDER.get(i)),
            (x - x.round()).abs() < 0.01,
        ) {
            (Some(m), true) => method_label(*m).to_string(),
            _ => String::new(),
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(7)
        .x_label_formatter(&label)
        .y_desc(figure.axis)
        .draw()?;
    for (i, _) in TABLE_ORDER.iter().enumerate() {
        let mut values: Vec<f64> = points.iter().filter(|p| p.0 == i).map(|p| p.2).collect();
        values.sort_by(f64::total_cmp);
        let Some(q) = five_numbers(&values) else {
            continue;
        };
        let x = (i + 1) as f32;
        let (half, cap) = (0.18f32, 0.08f32);
        let level = |v: f64| v as f32;
        chart.draw_series([
            PathElement::new(vec![(x, level(q[0])), (x, level(q[1]))], BLACK),
            PathElement::new(vec![(x, level(q[3])), (x, level(q[4]))], BLACK),
            PathElement::new(vec![(x - cap, level(q[0])), (x + cap, level(q[0]))], BLACK),
            PathElement::new(vec![(x - cap, level(q[4])), (x + cap, level(q[4]))], BLACK),
            PathElement::new(
                vec![(x - half, level(q[2])), (x + half, level(q[2]))],
                BLACK.stroke_width(3),
            ),
        ])?;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x - half, level(q[1])), (x + half, level(q[3]))],
            BLACK,
        )))?;
    }
    for (k, task) in tasks.iter().enumerate() {
        let colour = TASK_COLOURS[k % TASK_COLOURS.len()];
        let mine: Vec<&(usize, usize, f64)> = points.iter().filter(|p| p.1 == k).collect();
        chart
            .draw_series(mine.iter().enumerate().map(|(j, p)| {
                let spread = ((j % 9) as f32 - 4.0) * 0.025 + (k as f32 - 1.0) * 0.08;
                Circle::new(
                    ((p.0 + 1) as f32 + spread, p.2 as f32),
                    3,
                    colour.mix(0.7).filled(),
                )
            }))?
            .label(task.as_str())
            .legend(move |(x, y)| Circle::new((x, y), 4, colour.filled()));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()?;
    root.present()?;
    Ok(())
}

/// Smallest value, lower quartile, median, upper quartile and largest value of sorted
/// `values` (quartiles by linear interpolation between ranks); `None` when empty.
fn five_numbers(sorted: &[f64]) -> Option<[f64; 5]> {
    let last = sorted.len().checked_sub(1)?;
    let at = |q: f64| {
        let rank = q * last as f64;
        let (lo, hi) = (rank.floor() as usize, rank.ceil() as usize);
        sorted[lo] + (sorted[hi] - sorted[lo]) * (rank - lo as f64)
    };
    Some([sorted[0], at(0.25), at(0.5), at(0.75), sorted[last]])
}

/// The method's name as the thesis writes it.
pub fn method_label(m: Method) -> &'static str {
    match m {
        Method::Akl => "AKL",
        Method::Kd => "KD",
        Method::Macl => "mACL",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn five_numbers_interpolate_between_ranks() {
        assert_eq!(five_numbers(&[]), None);
        assert_eq!(five_numbers(&[2.0]), Some([2.0; 5]));
        assert_eq!(
            five_numbers(&[0.0, 1.0, 2.0, 3.0, 4.0]),
            Some([0.0, 1.0, 2.0, 3.0, 4.0])
        );
        assert_eq!(five_numbers(&[0.0, 10.0]), Some([0.0, 2.5, 5.0, 7.5, 10.0]));
    }

    /// A trial of `method` on `task` with `missed` keyframes missed.
    fn trial(task: &str, method: Method, missed: usize) -> Trial {
        Trial {
            participant: 1,
            experienced: false,
            method,
            position: 1,
            task: task.into(),
            seed: 0,
            frames: 10,
            duration_s: 0.1,
            unintended_line_chance: 0.0,
            unintended_lines: 0,
            queries: 0,
            yes: 0,
            no: 0,
            unknown: 0,
            suggestions: 0,
            errors_from_answers: 0,
            errors_avoided: 0,
            marks: 0,
            learn_error: None,
            learned_keyframes: 4,
            truth_keyframes: 4,
            missed_keyframes: missed,
            incorrect_keyframes: 0,
            keyframe_accuracy: 1.0,
            missed_poses: 0,
            incorrect_poses: 0,
            pose_accuracy: 1.0,
            missed_line_length: 0.0,
            incorrect_line_length: 0.0,
            constraint_accuracy: None,
            missed_constraints: 0,
            incorrect_constraints: 0,
            success: true,
            runtime_s: 0.01,
            executions: None,
            passed_executions: None,
            pass_rate: None,
            execute_error: None,
            spec: None,
        }
    }

    /// The numbers of attribute `name` in the SVG elements starting `<element` that also hold
    /// `with`.
    fn attribute(svg: &str, element: &str, with: &str, name: &str) -> Vec<Vec<f64>> {
        let key = format!(" {name}=\"");
        svg.lines()
            .filter(|l| l.starts_with(&format!("<{element} ")) && l.contains(with))
            .map(|l| {
                let from = l.find(&key).unwrap() + key.len();
                let value = &l[from..from + l[from..].find('"').unwrap()];
                value
                    .split([',', ' '])
                    .filter(|v| !v.is_empty())
                    .map(|v| v.parse().unwrap())
                    .collect()
            })
            .collect()
    }

    /// The figure holds its title, axis label, method and task labels, one point per trial in
    /// its task's colour, and a median bar per method with trials, at the median's height.
    #[test]
    fn a_figure_draws_every_trial_and_each_methods_median() {
        let mut trials = Vec::new();
        // Medians 1 (AKL) and 5 (KD), means 13/6 and 29/6.
        for (task, akl, kd) in [("a", [0, 0, 1], [4, 4, 5]), ("b", [1, 2, 9], [5, 5, 6])] {
            for (a, k) in akl.into_iter().zip(kd) {
                trials.push(trial(task, Method::Akl, a));
                trials.push(trial(task, Method::Kd, k));
            }
        }
        let svg = draw(&FIGURES[0], &trials, &["a".into(), "b".into()]).unwrap();
        let texts: Vec<&str> = svg
            .split("</text>")
            .filter_map(|t| t.rsplit_once('>').map(|(_, text)| text.trim()))
            .collect();
        for label in [FIGURES[0].title, "keyframes", "AKL", "KD", "mACL", "a", "b"] {
            assert!(texts.contains(&label), "no {label:?} in {texts:?}");
        }
        // Six trials per task, and the legend's mark.
        for colour in ["#1F77B4", "#FF7F0E"] {
            assert_eq!(attribute(&svg, "circle", colour, "cy").len(), 7, "{colour}");
        }
        // The value axis from the points (the legend's mark is drawn last): task b's highest
        // is 9 missed keyframes, task a's lowest 0.
        let b: Vec<f64> = attribute(&svg, "circle", "#FF7F0E", "cy")[..6]
            .iter()
            .map(|v| v[0])
            .collect();
        let zero = attribute(&svg, "circle", "#1F77B4", "cy")[..6]
            .iter()
            .map(|v| v[0])
            .fold(f64::MIN, f64::max);
        let per_unit = (zero - b.iter().cloned().fold(f64::MAX, f64::min)) / 9.0;
        assert!(per_unit > 10.0, "{per_unit}");
        // No trials of mACL: two median bars, KD's (drawn left of AKL's) at 5, AKL's at 1.
        let place = |m: Method| TABLE_ORDER.iter().position(|t| *t == m).unwrap();
        assert!(place(Method::Kd) < place(Method::Akl));
        let mut medians = attribute(&svg, "polyline", "stroke-width=\"3\"", "points");
        medians.sort_by(|p, q| p[0].total_cmp(&q[0]));
        let [kd_median, akl_median] = &medians[..] else {
            panic!("{medians:?}");
        };
        assert!(
            (zero - akl_median[1] - per_unit).abs() <= 1.5,
            "{akl_median:?}"
        );
        assert!(
            (zero - kd_median[1] - 5.0 * per_unit).abs() <= 1.5,
            "{kd_median:?}"
        );
    }

    #[test]
    fn every_figure_draws_an_svg_even_without_trials() {
        for f in &FIGURES {
            let svg = draw(f, &[], &["a".into()]).unwrap();
            assert!(
                svg.starts_with("<svg") && svg.contains("</svg>"),
                "{}",
                f.file
            );
            assert!(svg.contains("cf. thesis"));
        }
    }
}
