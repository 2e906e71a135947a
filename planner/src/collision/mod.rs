//! Collision checking of the arm, the hand and a held object against the world and the arm
//! itself, with parry3d shapes and cheap bounding-box culling before each exact test.
//!
//! Margins (from `robot.toml`): arm links are grown by `arm_margin`, hand links by
//! `hand_margin` and a held object by `held_margin` (by the larger of it and `hand_margin`
//! against movable objects and the arm) before being tested against the exact world
//! objects; two links are each grown by half of `self_margin` before being tested
//! against each other. Link pairs in `allowed_pairs` are never tested, nor `mount_links`
//! against the object under the robot base.
//!
//! Edges (straight joint-space segments, `Checker::edge`) are checked continuously in the
//! following sense: every clearance keeps at least half its margin everywhere along an edge
//! reported free. Each check on the edge proves a stretch around it free, as long as the
//! stretch is short enough that no point moves further than the clearance found at the
//! check plus half the margin. How far points move is bounded per collision element
//! (`Checker::sweep_bounds`) by the smaller of two bounds, each kept as a function of the share
//! of the stretch taken (`sweep::Motion`: a first-order part and the terms beyond it, which
//! shrink quadratically when a proof shortens the stretch): turning joint j by Δ moves a point
//! at distance r from its axis by at most r·|Δ|, where r is measured at the check and may grow
//! along the stretch by what the joints beyond j move the point; or, with the joints' motions
//! added as vectors (turns that carry the element opposite ways cancel), the element's
//! velocity at the check plus how far the rotation of the joints' axes and the motion of the
//! joints beyond can turn that velocity over the stretch. Both are computed for four chains at
//! a time in the lanes of SIMD vectors (`lanes`), bit for bit as one chain alone would give
//! them. A test moves points of every element through the forward kinematics and holds them
//! to the bound.
//!
//! Exact (parry) queries are asked only where cheaper bounds cannot settle a pair: bounding
//! boxes, segments, and balls that hold each element (`spheres`, property-tested never to
//! exceed the exact distance). Where an element's balls keep clear of an object but the pair
//! could still shorten the stretch, its exact distance is deferred to the end of the check and
//! taken for the pairs that limit the stretch most first, until the rest are settled by their
//! bounds: against the world, the stretch proved is the one every exact distance would prove.

mod checker;
mod cull;
mod exact;
mod held;
mod hit;
mod inside;
mod lanes;
mod minima;
mod model;
pub(crate) mod pair_table;
mod report;
mod scene;
mod spheres;
mod stored;
mod sweep;
#[cfg(test)]
pub(crate) mod tests;

pub use checker::Checker;
pub use exact::ExactShape;
pub use held::Held;
pub use hit::Hit;
pub(crate) use model::ElementBalls;
pub use model::{Margins, RobotCollision, TableSummary};
pub use report::{CheckReport, Clearance, Contact};
pub use scene::Scene;
pub use stored::{StoredTables, StoredTablesError};
