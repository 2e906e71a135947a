//! Which contacts a step of a task may make: the one set of rules that the planner's collision
//! checks and the simulation's contact verdicts both read.
//!
//! A step is described by what it manipulates ([`Step`]); [`Step::allowances`] turns that
//! into the objects the hand and the held object may touch ([`Allowances`]). Whether one
//! contact is allowed is then [`link_may_touch`] (a robot link with an object) or
//! [`held_may_touch`] (the object in the hand with another object):
//! - the mount links may touch the object the robot stands on;
//! - the hand links may touch the object they hold, and the objects the step grasps or has just
//!   released;
//! - the held object may touch the support it has not yet been lifted from, and the support
//!   it is being placed on (and what that support stands on: an object set down on a mat 1 mm
//!   thick overhangs it a hair above the shelf), but not press into it deeper than
//!   [`PRESS_DEPTH`];
//! - along a `move_in_line` that inserts the held object into a fixture (it ends within
//!   [`ENTRY_CLEARANCE`] of fixed objects: a tunnel's walls, a sleeve), the held object may
//!   brush against that fixture ([`held_may_brush`]): a compliant insertion on a real robot
//!   touches the walls it slides between. The planner still keeps its clearance from them; the
//!   simulation tolerates a light contact only (its limits are the execution's);
//! - nothing else may touch anything.

use akl_tsr::WORLD_FRAME;

/// Contacts allowed during part of a plan (see the module documentation of `task`).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Allowances {
    /// World objects the hand links may touch (the object being grasped or just released).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hand_may_touch: Vec<String>,
    /// World objects the held object may touch (the support it leaves or is placed on).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_may_touch: Vec<String>,
    /// Fixtures the held object may brush against lightly while it is inserted into them
    /// (judged by the simulation only: the planner keeps its clearance from them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_may_brush: Vec<String>,
}

impl Allowances {
    /// Whether nothing is allowed.
    pub(crate) fn is_empty(&self) -> bool {
        self.hand_may_touch.is_empty()
            && self.held_may_touch.is_empty()
            && self.held_may_brush.is_empty()
    }
}

/// How far (metres) the held object may press into a support it may touch: half a millimetre,
/// the single-precision noise of resting contact; a placement deeper than that presses the
/// object into its support.
pub const PRESS_DEPTH: f64 = 5e-4;

/// How close (metres) fixed objects come to the held object at the end of a `move_in_line` for
/// the line to insert it into them: 1 cm, wider than the built-in assembly's 6 mm tunnel
/// clearance and narrower than any gap a free placement leaves on purpose. Decided on the
/// world the planner perceives and the pose it plans, before any trial runs.
pub const ENTRY_CLEARANCE: f64 = 0.01;

/// What a robot link is, as far as contacts go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LinkRole {
    /// A hand or finger link: it may touch what it grasps, holds or releases.
    pub hand: bool,
    /// A link standing on the surface the robot is mounted on.
    pub mount: bool,
}

/// What a step of a task manipulates; `None` where it manipulates nothing of that kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Step<'a> {
    /// The object the hand is reaching for or closing on.
    pub grasping: Option<&'a str>,
    /// The object the hand has just let go of (while opening, and moving away from it).
    pub released: Option<&'a str>,
    /// The support the held object still rests on (it has not been lifted yet).
    pub resting_on: Option<&'a str>,
    /// The support the held object is being put on.
    pub placing_on: Option<&'a str>,
    /// What that support stands on.
    pub beneath: Option<&'a str>,
    /// The fixtures the held object is being inserted into (see [`ENTRY_CLEARANCE`]).
    pub entering: &'a [String],
}

impl Step<'_> {
    /// The contacts this step allows.
    pub fn allowances(&self) -> Allowances {
        let mut allow = Allowances::default();
        for object in [self.grasping, self.released].into_iter().flatten() {
            add(&mut allow.hand_may_touch, object);
        }
        let placing = [self.placing_on, self.placing_on.and(self.beneath)];
        for support in [self.resting_on].into_iter().chain(placing).flatten() {
            if support != WORLD_FRAME {
                add(&mut allow.held_may_touch, support);
            }
        }
        for fixture in self.entering {
            add(&mut allow.held_may_brush, fixture);
        }
        allow
    }
}

fn add(list: &mut Vec<String>, name: &str) {
    if !list.iter().any(|n| n == name) {
        list.push(name.to_string());
    }
}

/// Whether a link with `role` may touch `object` in a step that allows `allow`, with `held`
/// the object in the hand and `mount` the object the robot stands on.
pub fn link_may_touch(
    role: LinkRole,
    object: &str,
    held: Option<&str>,
    mount: Option<&str>,
    allow: &Allowances,
) -> bool {
    (role.mount && mount == Some(object))
        || (role.hand && (held == Some(object) || allow.hand_may_touch.iter().any(|n| n == object)))
}

/// Whether the held object may touch `object` in a step that allows `allow`.
pub fn held_may_touch(object: &str, allow: &Allowances) -> bool {
    allow.held_may_touch.iter().any(|n| n == object)
}

/// Whether the held object may brush against `object` (a fixture it is being inserted into)
/// in a step that allows `allow`: a light contact, within the execution's limits for it.
pub fn held_may_brush(object: &str, allow: &Allowances) -> bool {
    allow.held_may_brush.iter().any(|n| n == object)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HAND: LinkRole = LinkRole {
        hand: true,
        mount: false,
    };
    const ARM: LinkRole = LinkRole {
        hand: false,
        mount: false,
    };
    const BASE: LinkRole = LinkRole {
        hand: false,
        mount: true,
    };

    #[test]
    fn a_grasp_lets_only_the_hand_touch_only_its_object() {
        let allow = Step {
            grasping: Some("part"),
            resting_on: Some("shelf_1"),
            ..Step::default()
        }
        .allowances();
        assert!(link_may_touch(HAND, "part", None, None, &allow));
        assert!(!link_may_touch(ARM, "part", None, None, &allow));
        assert!(!link_may_touch(HAND, "shelf_1", None, None, &allow));
        assert!(held_may_touch("shelf_1", &allow));
        assert!(!held_may_touch("shelf_2", &allow));
    }

    #[test]
    fn the_base_touches_only_what_it_stands_on_and_the_hand_what_it_holds() {
        let none = Allowances::default();
        assert!(link_may_touch(BASE, "table", None, Some("table"), &none));
        assert!(!link_may_touch(BASE, "shelf_1", None, Some("table"), &none));
        assert!(!link_may_touch(ARM, "table", None, Some("table"), &none));
        assert!(link_may_touch(HAND, "part", Some("part"), None, &none));
        assert!(!link_may_touch(ARM, "part", Some("part"), None, &none));
    }

    #[test]
    fn an_insertion_lets_the_held_object_brush_only_the_fixture_it_enters() {
        let clamp = ["clamp_left".to_string(), "clamp_right".to_string()];
        let allow = Step {
            resting_on: Some("rail"),
            entering: &clamp,
            ..Step::default()
        }
        .allowances();
        assert!(held_may_brush("clamp_left", &allow) && held_may_brush("clamp_right", &allow));
        assert!(!held_may_touch("clamp_left", &allow));
        assert!(!held_may_brush("rail", &allow) && held_may_touch("rail", &allow));
        assert!(!held_may_brush("clamp_left", &Step::default().allowances()));
    }

    #[test]
    fn a_placement_may_touch_its_support_and_what_the_support_stands_on() {
        let allow = Step {
            placing_on: Some("mat"),
            beneath: Some("shelf_2"),
            ..Step::default()
        }
        .allowances();
        assert_eq!(allow.held_may_touch, ["mat", "shelf_2"]);
        let carrying = Step {
            beneath: Some("shelf_2"),
            ..Step::default()
        }
        .allowances();
        assert!(carrying.held_may_touch.is_empty());
    }

    #[test]
    fn placing_on_the_world_allows_nothing_and_names_are_not_repeated() {
        let allow = Step {
            grasping: Some("part"),
            released: Some("part"),
            placing_on: Some(WORLD_FRAME),
            ..Step::default()
        }
        .allowances();
        assert_eq!(allow.hand_may_touch, ["part"]);
        assert!(allow.held_may_touch.is_empty());
    }
}
