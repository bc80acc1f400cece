//! Finite elements of a cloth beside its springs: bending hinges and membrane triangles.

use bevy_ecs::prelude::*;
use glam::Mat2;

use crate::solver::elements::{
    BendingFace, BendingLaw, BendingRigidity, BendingSurface, MembraneElement, MembraneMaterial, QuadraticBending,
};

/// Bending over the cloth's surface (B3, Z2): hinges on interior edges and the faces whose
/// curvature their angles make (see [`crate::solver::elements::bending`]); under quadratic
/// bending only the constant Jacobian they make, the hinges and faces left empty.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct BendingHinges {
    /// `[o₁, o₂, i, j]` of each hinge (see [`crate::solver::elements::hinge`]).
    pub vertices: Vec<[u32; 4]>,
    /// Rest angle of each hinge [rad].
    pub rest_angle: Vec<f32>,
    /// The faces that bend.
    pub faces: Vec<BendingFace>,
    /// The moment–curvature law.
    pub law: BendingLaw,
    /// Rigidities by direction.
    pub rigidity: BendingRigidity,
    /// Quadratic bending's constant Jacobian (`law: Quadratic`), empty otherwise.
    pub quadratic: QuadraticBending,
}

impl Default for BendingHinges {
    fn default() -> Self {
        Self {
            vertices: Vec::new(),
            rest_angle: Vec::new(),
            faces: Vec::new(),
            law: BendingLaw::Linear,
            rigidity: BendingRigidity { warp: 0.0, weft: 0.0, twist: 0.0 },
            quadratic: QuadraticBending::default(),
        }
    }
}

impl BendingHinges {
    /// Whether the bending is quadratic: forces linear in the positions, and a constant
    /// Jacobian.
    pub fn is_quadratic(&self) -> bool {
        !self.quadratic.is_empty()
    }

    /// Number of hinges (interior edges that bend).
    pub fn hinge_count(&self) -> usize {
        match self.is_quadratic() {
            true => self.quadratic.hinge_count(),
            false => self.vertices.len(),
        }
    }

    /// The surface as the bending kernels see it (their faces, not quadratic bending's
    /// Jacobian).
    pub fn view(&self) -> BendingSurface<'_> {
        BendingSurface {
            hinges: &self.vertices,
            rest_angle: &self.rest_angle,
            faces: &self.faces,
            law: self.law,
            rigidity: self.rigidity,
            quadratic: &[],
        }
    }
}

/// Membrane triangles: anisotropic St. Venant–Kirchhoff in the warp/weft frame (Z2).
#[derive(Component, Debug, Clone, PartialEq)]
pub struct MembraneTriangles {
    /// Particle indices of each triangle: added with [`MembraneTriangles::push`] and
    /// removed with [`MembraneTriangles::retain`], so that each keeps its rest state.
    pub indices: Vec<[u32; 3]>,
    /// Each triangle's rest state ([`MembraneTriangles::element`]) in two columns: a
    /// [`MembraneElement`]'s `Mat2` is aligned to 16 bytes, so an element took 32 bytes
    /// for its 20 (24 bytes a particle of a sheet), and kept as four floats instead, its
    /// assembly's code took hang_256's 5 % longer (11.4 to 12.2 ms a frame against 10.7
    /// to 11.2, alternating).
    rest_inverses: Vec<Mat2>,
    rest_areas: Vec<f32>,
    /// Membrane constants shared by all triangles.
    pub material: MembraneMaterial,
}

impl Default for MembraneTriangles {
    fn default() -> Self {
        Self {
            indices: Vec::new(),
            rest_inverses: Vec::new(),
            rest_areas: Vec::new(),
            material: MembraneMaterial { d1: 0.0, d2: 0.0, d3: 0.0, d4: 0.0 },
        }
    }
}

impl MembraneTriangles {
    /// No triangles, of `material`, with room for `count`.
    pub fn with_capacity(material: MembraneMaterial, count: usize) -> Self {
        Self {
            indices: Vec::with_capacity(count),
            rest_inverses: Vec::with_capacity(count),
            rest_areas: Vec::with_capacity(count),
            material,
        }
    }

    /// Adds the triangle of particles `indices` with its rest state.
    pub fn push(&mut self, indices: [u32; 3], element: MembraneElement) {
        self.indices.push(indices);
        self.rest_inverses.push(element.rest_inverse);
        self.rest_areas.push(element.rest_area);
    }

    /// The rest state of triangle `m`.
    #[inline]
    pub fn element(&self, m: usize) -> MembraneElement {
        MembraneElement { rest_inverse: self.rest_inverses[m], rest_area: self.rest_areas[m] }
    }

    /// Every triangle's particles and rest state, in order.
    pub fn elements(&self) -> impl Iterator<Item = ([u32; 3], MembraneElement)> + '_ {
        (0..self.indices.len()).map(|m| (self.indices[m], self.element(m)))
    }

    /// Keeps the triangles `m` with `keep[m]`, in order.
    pub fn retain(&mut self, keep: &[bool]) {
        retain_kept(&mut self.indices, keep);
        retain_kept(&mut self.rest_inverses, keep);
        retain_kept(&mut self.rest_areas, keep);
    }
}

/// Keeps the entries of a column where `keep` is true.
pub(crate) fn retain_kept<T>(column: &mut Vec<T>, keep: &[bool]) {
    let mut k = keep.iter();
    column.retain(|_| *k.next().expect("one flag per entry"));
}

/// Edges whose strain is limited after every step (Z8).
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct StrainLimit {
    /// Limited particle pairs: warp and weft edges.
    pub pairs: Vec<[u32; 2]>,
    /// Their rest lengths [m].
    pub rest_length: Vec<f32>,
    /// Largest strain allowed [-]; no limit when the list is empty.
    pub max_strain: f32,
    /// Most projection sweeps per step.
    pub iterations: u32,
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// Triangles kept in columns read back as they were pushed, and a tear's retain keeps
    /// each triangle's particles with its own rest state.
    #[test]
    fn membrane_triangles_keep_each_rest_state_with_its_triangle() {
        let material = MembraneMaterial { d1: 300.0, d2: 120.0, d3: 40.0, d4: 60.0 };
        let mut membranes = MembraneTriangles::with_capacity(material, 3);
        let rest = |k: f32| [Vec3::ZERO, Vec3::new(0.1 * k, 0.0, 0.0), Vec3::new(0.02, 0.09 * k, 0.0)];
        let elements: Vec<MembraneElement> =
            (1..=3).map(|k| MembraneElement::from_rest(rest(k as f32), Vec3::X).expect("a proper triangle")).collect();
        for (k, element) in elements.iter().enumerate() {
            membranes.push([k as u32, k as u32 + 1, k as u32 + 2], *element);
        }
        assert_eq!(membranes.elements().map(|(_, e)| e).collect::<Vec<_>>(), elements);
        membranes.retain(&[true, false, true]);
        assert_eq!(membranes.indices, vec![[0, 1, 2], [2, 3, 4]]);
        assert_eq!((membranes.element(0), membranes.element(1)), (elements[0], elements[2]));
        assert!((membranes.element(1).rest_area - 0.5 * 0.3 * 0.27).abs() < 1e-7);
    }
}
