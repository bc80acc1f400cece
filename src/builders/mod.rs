//! Builders that turn descriptions into cloth data: grids, meshes from OBJ files, pin
//! selections and cuts.

pub mod disk;
pub mod grid;
pub mod mesh;
pub mod pins;
pub mod surface;
pub mod tear;

use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::components::{
    BendingHinges, ClothElements, ClothMaterial, MembraneTriangles, ParticleLayout, Particles, Springs, Triangles,
};
use crate::solver::ordering::{half_bandwidth, reverse_cuthill_mckee};

/// The structure of a freshly built cloth, before it becomes an entity.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothData {
    /// Particles at rest.
    pub particles: Particles,
    /// Springs at rest length.
    pub springs: Springs,
    /// Surface triangles.
    pub triangles: Triangles,
    /// Bending hinges (empty unless the material has bending).
    pub hinges: BendingHinges,
    /// Membrane triangles (empty unless the material has a membrane).
    pub membranes: MembraneTriangles,
    /// Grid regions and source numbering.
    pub layout: ParticleLayout,
}

impl ClothData {
    /// Its elements, what its topology is built from.
    pub fn elements(&self) -> ClothElements<'_> {
        ClothElements {
            springs: &self.springs,
            triangles: &self.triangles.indices,
            hinges: &self.hinges,
            membranes: &self.membranes,
        }
    }

    /// Renumbers the particles by reverse Cuthill–McKee so that particles that interact
    /// have close numbers (Bricis B8): the derivative blocks then sit near the diagonal and
    /// the solver's sweeps walk memory in order. For cloths built from meshes, whose file
    /// numbering is arbitrary; the layout keeps the mapping, so scenes still use the file's
    /// numbers. Call before surface elements are added. Returns the half-bandwidth before
    /// and after.
    pub fn renumber_for_locality(&mut self) -> (u32, u32) {
        let count = self.particles.len();
        let mut edges: Vec<[u32; 2]> = self.springs.pairs.clone();
        edges.extend(self.triangles.indices.iter().flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]]));
        let identity: Vec<u32> = (0..count as u32).collect();
        let before = half_bandwidth(&identity, &edges);
        let number = reverse_cuthill_mckee(count, &edges);
        let after = half_bandwidth(&number, &edges);
        if after >= before {
            return (before, before);
        }
        let mut source = vec![0usize; count];
        for (old, &new) in number.iter().enumerate() {
            source[new as usize] = old;
        }
        let p = &mut self.particles;
        let permute = |column: &mut Vec<glam::Vec3>| *column = source.iter().map(|&old| column[old]).collect();
        permute(&mut p.position);
        permute(&mut p.velocity);
        permute(&mut p.rest_position);
        permute(&mut p.force);
        p.inv_mass = source.iter().map(|&old| p.inv_mass[old]).collect();
        let map = |i: &mut u32| *i = number[*i as usize];
        self.springs.pairs.iter_mut().flatten().for_each(map);
        self.triangles.indices.iter_mut().flatten().for_each(map);
        self.layout.renumbered = if self.layout.renumbered.is_empty() {
            number
        } else {
            self.layout.renumbered.iter().map(|&old| if old == u32::MAX { old } else { number[old as usize] }).collect()
        };
        (before, after)
    }

    /// Adds the material's hinges and membrane triangles over the surface, with the warp
    /// along `warp` (world frame). Fails, saying why, where the bending's law does not
    /// suit the surface.
    pub fn add_surface_elements(&mut self, material: &ClothMaterial, warp: Vec3) -> Result<(), String> {
        let (x, triangles) = (&self.particles.position, &self.triangles.indices);
        if let Some(bending) = &material.bending {
            self.hinges = surface::build_bending(x, triangles, bending, warp)?;
        }
        if let Some(membrane) = material.membrane {
            self.membranes = surface::build_membranes(x, triangles, membrane, warp);
        }
        Ok(())
    }
}

/// Placement of a cloth in the world: rotate (Euler angles, X then Y then Z, in degrees),
/// then scale uniformly, then translate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Placement {
    /// Where the cloth's local origin goes [m].
    pub translation: Vec3,
    /// Rotation about X, then Y, then Z [degrees].
    pub rotation_deg: Vec3,
    /// Uniform scale [-], > 0.
    pub scale: f32,
}

impl Default for Placement {
    fn default() -> Self {
        Self { translation: Vec3::ZERO, rotation_deg: Vec3::ZERO, scale: 1.0 }
    }
}

impl Placement {
    /// The warp direction in the world for a grain angle `grain_deg` in the local XY plane.
    pub fn warp(self, grain_deg: f32) -> Vec3 {
        let g = grain_deg.to_radians();
        self.to_affine().transform_vector3(Vec3::new(g.cos(), g.sin(), 0.0)).normalize()
    }

    /// The affine map from the cloth's local frame to the world.
    pub fn to_affine(self) -> Affine3A {
        let r = self.rotation_deg * (std::f32::consts::PI / 180.0);
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            Quat::from_euler(EulerRot::XYZ, r.x, r.y, r.z),
            self.translation,
        )
    }
}

#[cfg(test)]
mod tests {
    use glam::Affine3A;

    use super::mesh::{TriangleMesh, build_from_mesh};
    use super::pins::PinSelection;
    use super::*;
    use crate::components::SpringCoefficients;

    #[test]
    fn renumbering_narrows_the_band_and_keeps_the_files_numbers_meaningful() {
        // A 6 × 6 grid of vertices listed in a scrambled order, one unused vertex first.
        let n = 6u32;
        let scramble = |i: u32| (i * 7) % (n * n) + 1;
        let mut positions = vec![Vec3::splat(99.0); (n * n + 1) as usize];
        for i in 0..n * n {
            positions[scramble(i) as usize] = Vec3::new((i % n) as f32, (i / n) as f32, 0.0);
        }
        let mut triangles = Vec::new();
        for r in 0..n - 1 {
            for c in 0..n - 1 {
                let at = |c: u32, r: u32| scramble(r * n + c);
                triangles.push([at(c, r), at(c + 1, r), at(c + 1, r + 1)]);
                triangles.push([at(c, r), at(c + 1, r + 1), at(c, r + 1)]);
            }
        }
        let spring = Some(SpringCoefficients { stiffness: 1.0, damping: 0.0 });
        let material =
            ClothMaterial { density: 1.0, stretch: spring, shear: None, bend: None, membrane: None, bending: None };
        let mut data = build_from_mesh(
            &TriangleMesh { positions: positions.clone(), triangles },
            Affine3A::IDENTITY,
            &material,
            "grid",
        )
        .expect("a valid mesh");
        let (before, after) = data.renumber_for_locality();
        assert!(after < before && after <= n + 2, "half-bandwidth {before} → {after}");
        // File vertex 8 is grid point scramble⁻¹(8); a pin by index still finds it.
        let pinned = PinSelection::Indices(vec![8]).resolve(&data.particles.position, &data.layout).expect("valid");
        assert_eq!(data.particles.position[pinned[0] as usize], positions[8]);
        let unused = PinSelection::Indices(vec![0]).resolve(&data.particles.position, &data.layout);
        assert!(unused.is_err_and(|e| e.to_string().contains("on no face")));
    }
}
