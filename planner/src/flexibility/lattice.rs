//! The TCP workspace as a cubic lattice: cells of one resolution, aligned so that the start
//! position is a cell centre, within the robot's reach and above its base, without the cells
//! whose centre lies inside furniture. A cell stands for its centre; a trace moves between
//! face neighbours (six per cell).

use akl_scene::{Shape, World};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;

/// Marks a missing neighbour or a grid point that is not a cell.
pub(super) const NONE: u32 = u32::MAX;

/// The six face-neighbour offsets, in the order of [`Lattice::neighbors`].
const OFFSETS: [[i64; 3]; 6] = [
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
];

/// The cells of the workspace and their neighbours.
#[derive(Debug, Clone)]
pub struct Lattice {
    resolution: f64,
    /// World position of grid point (0, 0, 0).
    origin: Vector3<f64>,
    /// Grid points along x, y and z.
    dims: [usize; 3],
    /// Cell id of every grid point, [`NONE`] for points that are not cells.
    ids: Vec<u32>,
    /// Grid coordinates of every cell.
    coords: Vec<[usize; 3]>,
    /// Six neighbour ids per cell ([`NONE`] where there is none).
    neighbors: Vec<u32>,
}

/// Whether world point `p` lies inside `shape` at `pose` (cylinders along their z axis).
pub(super) fn shape_contains(shape: &Shape, pose: &Pose, p: &Vector3<f64>) -> bool {
    let local = pose.inverse_transform_point(&(*p).into()).coords;
    match *shape {
        Shape::Box { size } => (0..3).all(|i| local[i].abs() <= 0.5 * size[i]),
        Shape::Cylinder { radius, length } => {
            local.z.abs() <= 0.5 * length && local.xy().norm() <= radius
        }
        Shape::Capsule { radius, length } => {
            let along = local.z.clamp(-0.5 * length, 0.5 * length);
            (local - Vector3::new(0.0, 0.0, along)).norm() <= radius
        }
        Shape::Sphere { radius } => local.norm() <= radius,
        Shape::Mesh { ref hull, .. } => hull.as_ref().is_some_and(|h| {
            // Inside every face's plane (faces counter-clockwise from outside).
            h.triangles.iter().all(|t| {
                let [a, b, c] = t.map(|i| h.vertices[i as usize].coords);
                (local - a).dot(&(b - a).cross(&(c - a))) <= 0.0
            })
        }),
    }
}

impl Lattice {
    /// The lattice of `resolution` (metres) whose cells have their centres within `reach` of
    /// `base` (the robot base pose) and not below it, aligned on `start`, without cells whose
    /// centre lies inside a fixed object of `world`.
    pub fn new(
        world: &World,
        base: &Pose,
        reach: f64,
        start: &Vector3<f64>,
        resolution: f64,
    ) -> Self {
        let centre = base.translation.vector;
        let up = base.rotation * Vector3::z();
        let mut origin = Vector3::zeros();
        let mut dims = [0usize; 3];
        for i in 0..3 {
            let below = ((start[i] - (centre[i] - reach)) / resolution).floor();
            origin[i] = start[i] - below * resolution;
            dims[i] = ((centre[i] + reach - origin[i]) / resolution).floor() as usize + 1;
        }
        let furniture: Vec<_> = world.objects.iter().filter(|o| !o.movable).collect();
        let mut ids = vec![NONE; dims[0] * dims[1] * dims[2]];
        let mut coords = Vec::new();
        for x in 0..dims[0] {
            for y in 0..dims[1] {
                for z in 0..dims[2] {
                    let p = origin + Vector3::new(x as f64, y as f64, z as f64) * resolution;
                    let d = p - centre;
                    if d.norm() > reach || d.dot(&up) < 0.0 {
                        continue;
                    }
                    if furniture
                        .iter()
                        .any(|o| shape_contains(&o.shape, &o.pose, &p))
                    {
                        continue;
                    }
                    ids[(x * dims[1] + y) * dims[2] + z] = coords.len() as u32;
                    coords.push([x, y, z]);
                }
            }
        }
        let mut lattice = Lattice {
            resolution,
            origin,
            dims,
            ids,
            coords,
            neighbors: Vec::new(),
        };
        let mut neighbors = Vec::with_capacity(6 * lattice.coords.len());
        for c in &lattice.coords {
            for o in OFFSETS {
                let g = [c[0] as i64 + o[0], c[1] as i64 + o[1], c[2] as i64 + o[2]];
                neighbors.push(lattice.id_at(g));
            }
        }
        lattice.neighbors = neighbors;
        lattice
    }

    /// Edge length of a cell (metres).
    pub(crate) fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.coords.len()
    }

    /// Whether the lattice has no cell.
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// Six neighbour ids per cell, [`NONE`] where there is none.
    pub(crate) fn neighbors(&self) -> &[u32] {
        &self.neighbors
    }

    /// World position of a cell's centre.
    pub(crate) fn centre(&self, cell: u32) -> Vector3<f64> {
        let c = self.coords[cell as usize];
        self.grid_point([c[0] as i64, c[1] as i64, c[2] as i64])
    }

    /// Grid coordinates of a cell.
    pub(crate) fn coords(&self, cell: u32) -> [i64; 3] {
        let c = self.coords[cell as usize];
        [c[0] as i64, c[1] as i64, c[2] as i64]
    }

    /// World position of a grid point (a cell's centre when it is a cell).
    pub(crate) fn grid_point(&self, g: [i64; 3]) -> Vector3<f64> {
        self.origin + Vector3::new(g[0] as f64, g[1] as f64, g[2] as f64) * self.resolution
    }

    /// The grid point whose cell contains `p` (nearest centre).
    pub(crate) fn grid_of(&self, p: &Vector3<f64>) -> [i64; 3] {
        let g = (p - self.origin) / self.resolution;
        [g.x.round() as i64, g.y.round() as i64, g.z.round() as i64]
    }

    /// The cell at grid point `g`, or [`NONE`] when it is outside the workspace or furniture.
    pub(crate) fn id_at(&self, g: [i64; 3]) -> u32 {
        if (0..3).any(|i| g[i] < 0 || g[i] >= self.dims[i] as i64) {
            return NONE;
        }
        let [x, y, z] = g.map(|v| v as usize);
        self.ids[(x * self.dims[1] + y) * self.dims[2] + z]
    }

    /// The cell containing `p`, if it is a cell of the workspace.
    pub(crate) fn cell_at(&self, p: &Vector3<f64>) -> Option<u32> {
        let id = self.id_at(self.grid_of(p));
        (id != NONE).then_some(id)
    }

    /// Shortest number of steps from any of `sources` (each entering at its own step count) to
    /// every cell, [`u32::MAX`] for cells that cannot be reached.
    pub(crate) fn distances(&self, sources: &[(u32, u32)]) -> Vec<u32> {
        distances(&self.neighbors, sources)
    }
}

/// Shortest number of steps over a neighbour table (six ids per cell) from any of `sources`
/// (each entering at its own step count) to every cell, [`u32::MAX`] where unreachable: a
/// breadth-first search with staggered sources.
pub(super) fn distances(neighbors: &[u32], sources: &[(u32, u32)]) -> Vec<u32> {
    let cells = neighbors.len() / 6;
    let mut dist = vec![u32::MAX; cells];
    let mut by_level: Vec<(u32, u32)> = sources.to_vec();
    by_level.sort_unstable_by_key(|&(_, d)| d);
    let mut next_source = 0;
    let mut frontier: Vec<u32> = Vec::new();
    let mut level = by_level.first().map_or(0, |&(_, d)| d);
    loop {
        while next_source < by_level.len() && by_level[next_source].1 <= level {
            let (c, d) = by_level[next_source];
            next_source += 1;
            if dist[c as usize] > d {
                dist[c as usize] = d;
                frontier.push(c);
            }
        }
        if frontier.is_empty() {
            if next_source == by_level.len() {
                break;
            }
            level = by_level[next_source].1;
            continue;
        }
        let mut next = Vec::new();
        for &c in &frontier {
            for &m in &neighbors[6 * c as usize..6 * c as usize + 6] {
                if m != NONE && dist[m as usize] > level + 1 {
                    dist[m as usize] = level + 1;
                    next.push(m);
                }
            }
        }
        frontier = next;
        level += 1;
    }
    dist
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::Object;
    use akl_tsr::pose::pose_from_xyz;

    fn world_with_box() -> World {
        World {
            robot_base: Pose::identity(),
            objects: vec![Object {
                name: "block".into(),
                shape: Shape::Box {
                    size: [0.2, 0.2, 0.2],
                },
                pose: pose_from_xyz([0.5, 0.0, 0.3]),
                movable: false,
                mass: 0.0,
                friction: 0.5,
            }],
        }
    }

    #[test]
    fn cells_inside_furniture_or_out_of_reach_are_not_cells() {
        let world = world_with_box();
        let start = Vector3::new(0.3, 0.0, 0.5);
        let lattice = Lattice::new(&world, &Pose::identity(), 1.0, &start, 0.05);
        let c = lattice.cell_at(&start).unwrap();
        assert!((lattice.centre(c) - start).norm() < 1e-12);
        assert_eq!(lattice.cell_at(&Vector3::new(0.5, 0.0, 0.3)), None);
        assert!(lattice.cell_at(&Vector3::new(0.5, 0.0, 0.45)).is_some());
        assert_eq!(lattice.cell_at(&Vector3::new(0.0, 0.0, 1.2)), None);
        assert_eq!(lattice.cell_at(&Vector3::new(0.3, 0.0, -0.1)), None);
        for c in 0..lattice.len() as u32 {
            assert!(lattice.centre(c).norm() <= 1.0 + 1e-12);
        }
    }

    #[test]
    fn neighbours_are_one_step_apart_both_ways() {
        let lattice = Lattice::new(
            &world_with_box(),
            &Pose::identity(),
            0.6,
            &Vector3::new(0.3, 0.0, 0.5),
            0.1,
        );
        for c in 0..lattice.len() as u32 {
            for &n in &lattice.neighbors()[6 * c as usize..6 * c as usize + 6] {
                if n == NONE {
                    continue;
                }
                let d = (lattice.centre(n) - lattice.centre(c)).norm();
                assert!((d - 0.1).abs() < 1e-9);
                assert!(lattice.neighbors()[6 * n as usize..6 * n as usize + 6].contains(&c));
            }
        }
    }

    #[test]
    fn distances_count_steps_from_staggered_sources() {
        let lattice = Lattice::new(
            &World {
                robot_base: Pose::identity(),
                objects: Vec::new(),
            },
            &Pose::identity(),
            1.0,
            &Vector3::new(0.0, 0.0, 0.5),
            0.1,
        );
        let a = lattice.cell_at(&Vector3::new(0.0, 0.0, 0.5)).unwrap();
        let b = lattice.cell_at(&Vector3::new(0.3, 0.0, 0.5)).unwrap();
        let c = lattice.cell_at(&Vector3::new(0.6, 0.0, 0.5)).unwrap();
        let d = lattice.distances(&[(a, 0)]);
        assert_eq!(d[b as usize], 3);
        assert_eq!(d[c as usize], 6);
        let d = lattice.distances(&[(a, 0), (c, 1)]);
        assert_eq!(d[b as usize], 3);
        assert_eq!(
            d[lattice.cell_at(&Vector3::new(0.5, 0.0, 0.5)).unwrap() as usize],
            2
        );
    }
}
