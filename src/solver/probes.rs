//! Measurements of a cloth's state, reported per frame.

use std::ops::Range;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::reduce;
use crate::components::{MembraneTriangles, Springs};

/// Kinetic energy `Σ ½ m |v|²` [J], in parallel (the same on any number of threads).
pub fn kinetic_energy(v: &[Vec3], inv_mass: &[f32]) -> f64 {
    reduce::sum(v.len(), |i| 0.5 * f64::from(v[i].length_squared() / inv_mass[i]))
}

/// The most stretched of the edges the cloth resists stretching along (each spring, then
/// each side of each membrane triangle, whose rest length comes from the rest positions
/// `rest`), with its two particles and its strain (length over rest length, minus one);
/// the first of equals; `None` without edges. In parallel, the same on any number of
/// threads.
pub fn most_stretched_edge(
    x: &[Vec3],
    rest: &[Vec3],
    springs: &Springs,
    membranes: &MembraneTriangles,
) -> Option<([u32; 2], f32)> {
    let strain = |[i, j]: [u32; 2], rest_length: f32| (x[i as usize] - x[j as usize]).length() / rest_length - 1.0;
    let edge = |e: usize| {
        if e < springs.len() {
            (springs.pairs[e], strain(springs.pairs[e], springs.rest_length[e]))
        } else {
            let side = e - springs.len();
            let triangle = membranes.indices[side / 3];
            let pair = [triangle[side % 3], triangle[(side + 1) % 3]];
            (pair, strain(pair, (rest[pair[0] as usize] - rest[pair[1] as usize]).length()))
        }
    };
    let worse = |first: Option<([u32; 2], f32)>, second: Option<([u32; 2], f32)>| match (first, second) {
        (Some(a), Some(b)) => Some(if b.1 > a.1 { b } else { a }),
        (a, None) => a,
        (None, b) => b,
    };
    let edges = springs.len() + 3 * membranes.indices.len();
    reduce::reduce(0..edges, &|range: Range<usize>| range.map(edge).fold(None, |w, e| worse(w, Some(e))), &worse)
}

/// A measurement of one cloth that a scene asks for by configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ClothProbe {
    /// `cantilever_angle_deg`: the angle below horizontal [degrees] of the line from the
    /// table `edge` [m] to the strip's tip, the particles furthest along `direction` in
    /// the rest shape (Peirce's cantilever test, ASTM D1388).
    CantileverAngle {
        /// Name of the cloth.
        cloth: String,
        /// The table edge [m].
        edge: Vec3,
        /// Direction of the strip from the edge, horizontal.
        direction: Vec3,
    },
    /// `drape_coefficient`: Cusick's (shadow − pedestal) / (specimen − pedestal) areas, the
    /// shadow being the cloth's area projected on the horizontal plane.
    DrapeCoefficient {
        /// Name of the cloth.
        cloth: String,
        /// Radius of the pedestal disk [m].
        pedestal_radius: f32,
        /// Radius of the flat specimen [m].
        specimen_radius: f32,
    },
    /// `mean_stress_n_per_m`: area-weighted mean of the membrane's normal Cauchy stress
    /// resultant along `direction` [N/m].
    MeanStress {
        /// Name of the cloth.
        cloth: String,
        /// The direction of the normal stress.
        direction: Vec3,
    },
}

impl ClothProbe {
    /// The name the probe reports under.
    pub fn name(&self) -> &'static str {
        match self {
            ClothProbe::CantileverAngle { .. } => "cantilever_angle_deg",
            ClothProbe::DrapeCoefficient { .. } => "drape_coefficient",
            ClothProbe::MeanStress { .. } => "mean_stress_n_per_m",
        }
    }

    /// The cloth it measures.
    pub fn cloth(&self) -> &str {
        match self {
            ClothProbe::CantileverAngle { cloth, .. }
            | ClothProbe::DrapeCoefficient { cloth, .. }
            | ClothProbe::MeanStress { cloth, .. } => cloth,
        }
    }

    /// Measures the cloth at positions `x` (rest positions `rest`).
    pub fn measure(&self, x: &[Vec3], rest: &[Vec3], triangles: &[[u32; 3]], membranes: &MembraneTriangles) -> f64 {
        match self {
            ClothProbe::CantileverAngle { edge, direction, .. } => {
                f64::from(cantilever_angle_deg(x, rest, *edge, *direction))
            }
            ClothProbe::DrapeCoefficient { pedestal_radius, specimen_radius, .. } => {
                let pedestal = std::f32::consts::PI * pedestal_radius * pedestal_radius;
                let specimen = std::f32::consts::PI * specimen_radius * specimen_radius;
                let shadow = shadow_area(x, triangles, specimen_radius / 400.0);
                f64::from((shadow - pedestal) / (specimen - pedestal))
            }
            ClothProbe::MeanStress { direction, .. } => f64::from(mean_normal_stress(x, membranes, *direction)),
        }
    }
}

/// Angle below horizontal [degrees] from `edge` to the centroid of the particles whose
/// rest positions lie furthest along `direction`.
pub fn cantilever_angle_deg(x: &[Vec3], rest: &[Vec3], edge: Vec3, direction: Vec3) -> f32 {
    let reach = |i: usize| rest[i].dot(direction);
    let furthest = (0..rest.len()).map(reach).fold(f32::NEG_INFINITY, f32::max);
    let tip: Vec<Vec3> = (0..rest.len()).filter(|&i| reach(i) >= furthest - 1e-6).map(|i| x[i]).collect();
    let tip = tip.iter().sum::<Vec3>() / tip.len() as f32;
    let offset = tip - edge;
    (-offset.y).atan2(Vec3::new(offset.x, 0.0, offset.z).length()).to_degrees()
}

/// Area [m²] of the union of the triangles projected on the horizontal (XZ) plane,
/// rasterised on square cells of side `cell` [m].
pub fn shadow_area(x: &[Vec3], triangles: &[[u32; 3]], cell: f32) -> f32 {
    let (mut min, mut max) = (glam::Vec2::splat(f32::INFINITY), glam::Vec2::splat(f32::NEG_INFINITY));
    for p in x {
        let q = glam::Vec2::new(p.x, p.z);
        min = min.min(q);
        max = max.max(q);
    }
    let columns = ((max.x - min.x) / cell).ceil() as usize + 1;
    let rows = ((max.y - min.y) / cell).ceil() as usize + 1;
    let mut covered = vec![false; columns * rows];
    for tri in triangles {
        let [a, b, c] = tri.map(|p| glam::Vec2::new(x[p as usize].x, x[p as usize].z) - min);
        let lo = a.min(b).min(c) / cell;
        let hi = a.max(b).max(c) / cell;
        let twice_area = (b - a).perp_dot(c - a);
        if twice_area == 0.0 {
            continue;
        }
        for row in lo.y.floor().max(0.0) as usize..=(hi.y.ceil() as usize).min(rows - 1) {
            for column in lo.x.floor().max(0.0) as usize..=(hi.x.ceil() as usize).min(columns - 1) {
                let p = glam::Vec2::new(column as f32 + 0.5, row as f32 + 0.5) * cell;
                let w0 = (b - p).perp_dot(c - p) / twice_area;
                let w1 = (c - p).perp_dot(a - p) / twice_area;
                if w0 >= 0.0 && w1 >= 0.0 && w0 + w1 <= 1.0 {
                    covered[row * columns + column] = true;
                }
            }
        }
    }
    covered.iter().filter(|c| **c).count() as f32 * cell * cell
}

/// Area-weighted mean over membrane triangles of `dᵀ σ d` [N/m], σ the Cauchy stress
/// resultant `F S Fᵀ / J` and `d` the unit `direction`.
pub fn mean_normal_stress(x: &[Vec3], membranes: &MembraneTriangles, direction: Vec3) -> f32 {
    let d = direction.normalize();
    let (mut weighted, mut area) = (0.0f64, 0.0f64);
    for (tri, element) in membranes.elements() {
        let corners = tri.map(|p| x[p as usize]);
        let current = super::geometry::triangle_area(corners[0], corners[1], corners[2]);
        let f = element.deformation(corners);
        let (e11, e22, e12) = f.green_strain();
        let (s11, s22, s12) = membranes.material.stress(e11, e22, e12);
        // dᵀ F S Fᵀ d / J with J = current / rest area; weighted by the current area this
        // is the rest area times the quadratic form.
        let (u, w) = (f.warp.dot(d), f.weft.dot(d));
        let normal = u * u * s11 + 2.0 * u * w * s12 + w * w * s22;
        weighted += f64::from(element.rest_area * normal);
        area += f64::from(current);
    }
    if area > 0.0 { (weighted / area) as f32 } else { 0.0 }
}
