//! Untangling cloth that starts intersecting (Z6): layers tried on separately and then
//! superposed, or dropped through each other. Continuous collision keeps an untangled
//! cloth untangled, but it also keeps a tangled one tangled: it stops every vertex at the
//! surface it would have to pass back through. So, as in Zheng's workflow (§4.4), at the
//! start of a step the edges that cross a triangle are found, the vertices on the wrong
//! side are moved back through, and those vertices are exempt from the step's contact
//! stages.
//!
//! Which side is wrong comes from the layers: a cloth of a higher `layer` belongs on the
//! side of a lower layer's triangle normals. Within one layer there is no order to go
//! by; the end of the crossing edge nearer the other triangle's plane is taken back, the
//! shortest way out (a local stand-in for Zheng's smaller-region rule).
//!
//! The wrong-side region grows from each crossing edge's wrong end along edges that
//! cross nothing, through vertices behind the crossed triangle's plane, so a whole flap
//! that went through moves back together rather than being stretched at its rim. Region
//! vertices move by at most [`UNTANGLE_SPEED`] `h` a step towards and through that plane
//! (a position correction: no velocity is added, only the approach is removed), until
//! they are the pair's separation beyond it.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::bvh::{Aabb, Bvh};
use super::intersection::segment_crosses_triangle;
use super::self_contact::ContactMesh;
use crate::solver::PARALLEL_MIN_LEN;

/// Fastest a tangled vertex is moved back through [m/s].
pub const UNTANGLE_SPEED: f32 = 0.5;

/// No seed owns the vertex.
const FREE: u32 = u32::MAX;

/// Where a region must go: towards and through the plane `direction · x = level`.
#[derive(Debug, Clone, Copy)]
struct Seed {
    direction: Vec3,
    level: f32,
}

impl Seed {
    /// How far `x` is behind the plane (positive on the wrong side) [m].
    fn depth(&self, x: Vec3) -> f32 {
        self.level - self.direction.dot(x)
    }
}

/// The untangling stage of self-contact, and what it keeps between steps.
#[derive(Debug, Clone)]
pub struct Untangler {
    /// Whether the next step must look for crossings: at first, and while the last look
    /// found some or impact zones could have let a pinned vertex through.
    watching: bool,
    /// Vertices moved back this step: the contact stages leave their pairs alone.
    pub exempt: Vec<bool>,
    /// The seed that owns each vertex this step, or [`FREE`].
    owner: Vec<u32>,
    /// Vertex–edge adjacency (compressed rows): neighbour and edge index.
    first: Vec<u32>,
    neighbours: Vec<(u32, u32)>,
}

impl Default for Untangler {
    fn default() -> Self {
        Self { watching: true, exempt: Vec::new(), owner: Vec::new(), first: Vec::new(), neighbours: Vec::new() }
    }
}

impl Untangler {
    /// Whether this step looks for crossings.
    pub fn watching(&self) -> bool {
        self.watching
    }

    /// Asks the next step to look for crossings again.
    pub fn watch(&mut self) {
        self.watching = true;
    }

    /// Forgets the exemptions of the last step.
    pub fn clear(&mut self, vertices: usize) {
        self.exempt.clear();
        self.exempt.resize(vertices, false);
    }

    /// Finds the edges of `mesh` that cross one of its triangles at `x0` (candidates from
    /// `tree`, whose boxes must contain the triangles at `x0`), and moves the wrong-side
    /// regions back through by changing the step's end positions `x1` and end velocities
    /// `v`. Returns the number of crossings found.
    pub fn run(&mut self, mesh: &ContactMesh, tree: &Bvh, h: f32, x0: &[Vec3], x1: &mut [Vec3], v: &mut [Vec3]) -> u32 {
        self.clear(mesh.len());
        let crossings = crossings(mesh, tree, x0);
        self.watching = !crossings.is_empty();
        if crossings.is_empty() {
            return 0;
        }
        let seeds = self.grow_regions(mesh, &crossings, x0);
        for k in 0..mesh.len() {
            let owner = self.owner[k];
            if owner == FREE {
                continue;
            }
            self.exempt[k] = true;
            if mesh.impulse_inv_mass[k] == 0.0 {
                // Pinned or resting on a body: the other side must do all the moving.
                continue;
            }
            let seed = seeds[owner as usize];
            let wanted = seed.depth(x1[k]) + 2.0 * mesh.half_gap[k];
            if wanted > 0.0 {
                x1[k] += wanted.min(UNTANGLE_SPEED * h) * seed.direction;
            }
            let approach = v[k].dot(seed.direction);
            if approach < 0.0 {
                v[k] -= approach * seed.direction;
            }
        }
        crossings.len() as u32
    }

    /// Labels every vertex with the seed whose wrong-side region holds it (breadth first
    /// from the crossings in order, so the labels do not depend on threads) and returns
    /// the seeds.
    fn grow_regions(&mut self, mesh: &ContactMesh, crossings: &[(u32, u32)], x0: &[Vec3]) -> Vec<Seed> {
        self.build_adjacency(mesh);
        let mut crossing_edge = vec![false; mesh.edges.len()];
        for &(e, _) in crossings {
            crossing_edge[e as usize] = true;
        }
        self.owner.clear();
        self.owner.resize(mesh.len(), FREE);
        let mut seeds = Vec::with_capacity(crossings.len());
        let mut queue = std::collections::VecDeque::new();
        for &(e, t) in crossings {
            let (bad, seed) = wrong_end(mesh, e, t, x0);
            if self.owner[bad as usize] == FREE {
                self.owner[bad as usize] = seeds.len() as u32;
                queue.push_back(bad);
            }
            seeds.push(seed);
        }
        while let Some(k) = queue.pop_front() {
            let owner = self.owner[k as usize];
            let seed = seeds[owner as usize];
            let row = self.first[k as usize] as usize..self.first[k as usize + 1] as usize;
            for &(j, e) in &self.neighbours[row] {
                if !crossing_edge[e as usize] && self.owner[j as usize] == FREE && seed.depth(x0[j as usize]) > 0.0 {
                    self.owner[j as usize] = owner;
                    queue.push_back(j);
                }
            }
        }
        seeds
    }

    fn build_adjacency(&mut self, mesh: &ContactMesh) {
        let mut degree = vec![0u32; mesh.len() + 1];
        for &[a, b] in &mesh.edges {
            degree[a as usize + 1] += 1;
            degree[b as usize + 1] += 1;
        }
        for k in 1..degree.len() {
            degree[k] += degree[k - 1];
        }
        self.first.clone_from(&degree);
        self.neighbours.clear();
        self.neighbours.resize(mesh.edges.len() * 2, (0, 0));
        for (e, &[a, b]) in mesh.edges.iter().enumerate() {
            for (from, to) in [(a, b), (b, a)] {
                self.neighbours[degree[from as usize] as usize] = (to, e as u32);
                degree[from as usize] += 1;
            }
        }
    }
}

/// Every (edge, triangle) pair of `mesh` that shares no vertex and crosses at `x0`, in
/// edge order; exact in double precision.
fn crossings(mesh: &ContactMesh, tree: &Bvh, x0: &[Vec3]) -> Vec<(u32, u32)> {
    (0..mesh.edges.len() as u32)
        .into_par_iter()
        .with_min_len(PARALLEL_MIN_LEN)
        .flat_map_iter(|e| {
            let [a, b] = mesh.edges[e as usize];
            let (p, q) = (x0[a as usize], x0[b as usize]);
            let mut found = Vec::new();
            tree.query(&Aabb::around([p, q]), |t| {
                let tri = mesh.triangles[t as usize];
                if !tri.contains(&a)
                    && !tri.contains(&b)
                    && segment_crosses_triangle(p.as_dvec3(), q.as_dvec3(), tri.map(|k| x0[k as usize].as_dvec3()))
                {
                    found.push(t);
                }
            });
            found.sort_unstable();
            found.into_iter().map(move |t| (e, t))
        })
        .collect()
}

/// The end of crossing edge `e` that is on the wrong side of triangle `t`, and where it
/// must go.
fn wrong_end(mesh: &ContactMesh, e: u32, t: u32, x0: &[Vec3]) -> (u32, Seed) {
    let [a, b] = mesh.edges[e as usize];
    let tri = mesh.triangles[t as usize];
    let [p, q, r]: [DVec3; 3] = tri.map(|k| x0[k as usize].as_dvec3());
    let normal = (q - p).cross(r - p).normalize_or_zero();
    let side = |k: u32| (x0[k as usize].as_dvec3() - p).dot(normal);
    let (edge_layer, triangle_layer) = (mesh.layer[a as usize], mesh.layer[tri[0] as usize]);
    // The wrong end, and the side of the plane it belongs on (+1: the normal's side).
    let (bad, belongs) = if edge_layer != triangle_layer {
        let belongs = if edge_layer > triangle_layer { 1.0 } else { -1.0 };
        (if side(a) * belongs < 0.0 { a } else { b }, belongs)
    } else {
        let bad = if side(a).abs() <= side(b).abs() { a } else { b };
        (bad, -side(bad).signum())
    };
    let direction = (normal * belongs).as_vec3();
    (bad, Seed { direction, level: direction.dot(p.as_vec3()) })
}

#[cfg(test)]
mod tests {
    use glam::Vec3Swizzles;

    use super::*;
    use crate::collision::intersection::count_self_intersections;

    /// Two square sheets of `n` × `n` vertices and side 1: the first flat at height 0,
    /// the second tilted 20° about X through the same centre, so they cross along a line.
    fn crossed_sheets(n: u32, layers: [u32; 2]) -> (ContactMesh, Vec<Vec3>) {
        let mut mesh = ContactMesh::default();
        let mut x = Vec::new();
        let tilt = glam::Quat::from_rotation_x(20f32.to_radians());
        for (sheet, layer) in layers.into_iter().enumerate() {
            let offset = x.len() as u32;
            for j in 0..n {
                for i in 0..n {
                    let flat = Vec3::new(i as f32 / (n - 1) as f32 - 0.5, 0.0, j as f32 / (n - 1) as f32 - 0.5);
                    x.push(if sheet == 0 { flat } else { tilt * flat });
                }
            }
            for j in 0..n - 1 {
                for i in 0..n - 1 {
                    let k = offset + j * n + i;
                    // Wound so that the normals point up (+Y).
                    mesh.triangles.push([k, k + n, k + 1]);
                    mesh.triangles.push([k + 1, k + n, k + n + 1]);
                }
            }
            let count = (n * n) as usize;
            mesh.layer.extend(std::iter::repeat_n(layer, count));
        }
        mesh.edges = ContactMesh::edges_of(&mesh.triangles);
        let count = x.len();
        mesh.inv_mass = vec![1.0; count];
        mesh.impulse_inv_mass = vec![1.0; count];
        mesh.half_gap = vec![0.005; count];
        mesh.friction = vec![0.0; count];
        (mesh, x)
    }

    /// Steps the sheets at rest through the untangler alone until no edge crosses a
    /// triangle; returns the steps taken.
    fn untangle(mesh: &ContactMesh, x: &mut [Vec3], max_steps: u32) -> u32 {
        let mut untangler = Untangler::default();
        let h = 0.01;
        for step in 0..max_steps {
            let boxes: Vec<Aabb> =
                mesh.triangles.iter().map(|t| Aabb::around(t.iter().map(|&k| x[k as usize]))).collect();
            let tree = Bvh::build(&boxes);
            let x0 = x.to_vec();
            let mut v = vec![Vec3::ZERO; x.len()];
            if untangler.run(mesh, &tree, h, &x0, x, &mut v) == 0 {
                return step;
            }
            assert!(v.iter().all(|v| *v == Vec3::ZERO), "untangling adds no velocity");
        }
        panic!("still tangled after {max_steps} steps");
    }

    #[test]
    fn crossed_layers_end_apart_in_their_layer_order() {
        for (layers, upper) in [([0, 1], 1), ([1, 0], 0)] {
            let (mesh, mut x) = crossed_sheets(12, layers);
            assert!(count_self_intersections(&x, &mesh.triangles) > 0, "the sheets start crossed");
            let steps = untangle(&mesh, &mut x, 200);
            assert_eq!(count_self_intersections(&x, &mesh.triangles), 0);
            // Every vertex of the upper sheet over the other is above it there.
            let per_sheet = 144;
            let (first, second) = x.split_at(per_sheet);
            let (top, bottom) = if upper == 1 { (second, first) } else { (first, second) };
            for p in top {
                let below = bottom
                    .iter()
                    .min_by(|a, b| a.xz().distance(p.xz()).total_cmp(&b.xz().distance(p.xz())))
                    .expect("vertices");
                if below.xz().distance(p.xz()) < 0.05 {
                    assert!(p.y > below.y, "layer {upper} is on top after {steps} steps: {p} over {below}");
                }
            }
        }
    }

    #[test]
    fn pinned_vertices_stay_and_the_other_side_moves() {
        let (mut mesh, mut x) = crossed_sheets(8, [0, 1]);
        mesh.impulse_inv_mass[..64].fill(0.0);
        let flat: Vec<Vec3> = x[..64].to_vec();
        untangle(&mesh, &mut x, 200);
        assert_eq!(&x[..64], &flat[..], "the held sheet did not move");
        assert_eq!(count_self_intersections(&x, &mesh.triangles), 0);
    }
}
