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
//!   it is being placed on, but not press into it deeper than [`PRESS_DEPTH`];
//! - nothing else may touch anything.

use crate::collision::Allowances;
use akl_tsr::WORLD_FRAME;

/// How far (metres) the held object may press into a support it may touch: half a millimetre,
/// the single-precision noise of resting contact; a placement deeper than that presses the
/// object into its support.
pub const PRESS_DEPTH: f64 = 5e-4;

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
}

impl Step<'_> {
    /// The contacts this step allows.
    pub fn allowances(&self) -> Allowances {
        let mut allow = Allowances::default();
        for object in [self.grasping, self.released].into_iter().flatten() {
            add(&mut allow.hand_may_touch, object);
        }
        for support in [self.resting_on, self.placing_on].into_iter().flatten() {
            if support != WORLD_FRAME {
                add(&mut allow.held_may_touch, support);
            }
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
