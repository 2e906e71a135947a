//! Meshes: triangle meshes read from files, and the convex hulls made of them.
//!
//! One module for every mesh AKL reads: a task's objects given as a mesh file
//! (`{"type": "mesh", "file": "part.stl"}`) and, for robot descriptions, link geometry.
//! Files are read with `mesh-loader` (STL, OBJ, COLLADA), the hull is parry's.
//!
//! - [`load`]: the triangles of a file, in metres, every mesh of the file merged.
//! - [`ConvexHull`]: the convex hull of a set of points, centred on the middle of its bounding
//!   box, with its volume and centre of mass (a uniform solid), as planning and simulation use
//!   it.
//! - [`enclosing_capsules`]: a few [`Capsule`]s whose union holds every triangle of a mesh, as
//!   tight as the search finds: the collision model a planner gives a robot link.

mod enclose;
mod hull;
mod read;

pub use enclose::{enclosing_capsules, Capsule};
pub use hull::ConvexHull;
pub use read::{load, load_bytes, TriMesh};

use std::path::PathBuf;
use thiserror::Error;

/// A mesh that cannot be used, naming its file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The file cannot be read or parsed.
    #[error("{path}: {problem}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        problem: String,
    },
    /// The points span no volume (fewer than four, or all on a plane).
    #[error("{path}: its {points} points span no volume, so it has no solid hull")]
    Flat {
        /// The file.
        path: PathBuf,
        /// How many points it has.
        points: usize,
    },
}
