//! Goal check: the task's goal predicates on the settled world and the objects' simulated
//! paths, and every movable object at rest once settled.

use crate::report::{Cause, Failure};
use crate::simulate::observations::Observations;
use crate::world::resting;
use akl_scene::{GoalCheck, Task};

/// The goal checks, and a failure for each that does not hold, at the end of settling.
pub(crate) fn check(
    task: &Task,
    obs: &Observations,
    rest_speed: f64,
) -> (Vec<GoalCheck>, Vec<Failure>) {
    let mut goals: Vec<GoalCheck> = match &obs.settled {
        Some(world) => task.check_goals(world, &obs.paths),
        None => Vec::new(),
    };
    goals.push(rest(&obs.speeds, rest_speed));
    let failures = goals
        .iter()
        .filter(|g| !g.holds)
        .map(|g| {
            Failure::new(Cause::GoalNotMet, format!("{}: {}", g.goal, g.detail))
                .at_time(obs.simulated)
        })
        .collect();
    (goals, failures)
}

/// The rest check: every movable object slower than `max_speed` (m/s, and 10 × that in rad/s)
/// once settled; `speeds` are (name, linear, angular) per movable object.
pub(crate) fn rest(speeds: &[(String, f64, f64)], max_speed: f64) -> GoalCheck {
    let moving: Vec<String> = speeds
        .iter()
        .filter(|(_, v, w)| !resting(*v, *w, max_speed))
        .map(|(n, v, w)| format!("{n} ({v:.3} m/s, {w:.2} rad/s)"))
        .collect();
    GoalCheck {
        goal: "at rest".into(),
        holds: moving.is_empty(),
        detail: if moving.is_empty() {
            "every object at rest".into()
        } else {
            format!("still moving: {}", moving.join(", "))
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_objects_fail_the_rest_check() {
        assert!(rest(&[("a".into(), 0.001, 0.01)], 0.01).holds);
        let bad = rest(&[("a".into(), 0.001, 0.01), ("b".into(), 0.2, 0.0)], 0.01);
        assert!(!bad.holds && bad.detail.contains('b'), "{}", bad.detail);
    }
}
