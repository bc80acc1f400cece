//! Cloth from a triangle mesh (Wavefront OBJ): particles from vertices, masses from areas,
//! structural springs from edges, bend springs across interior edges.

use std::path::Path;

use glam::{Affine3A, Vec3};

use super::ClothData;
use super::surface::interior_edges;
use crate::components::{
    BendingHinges, ClothMaterial, MembraneTriangles, ParticleLayout, Particles, SpringCoefficients, SpringKind,
    Springs, Triangles,
};
use crate::memory::release;
use crate::solver::geometry::{lumped_masses, triangle_area};

/// A triangle mesh: vertex positions and counter-clockwise triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions [m].
    pub positions: Vec<Vec3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh could not be read or used.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read.
    #[error("cannot read mesh file {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A line of the file is not valid OBJ.
    #[error("{path}:{line}: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The mesh cannot make a cloth.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// Reads the vertices and faces of an OBJ file; polygons are split into fans. Texture and
/// normal indices (`f 1/2/3 ...`) and every other statement are ignored.
pub fn read_obj(path: &Path) -> Result<TriangleMesh, MeshError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| MeshError::Io { path: name.clone(), source })?;
    parse_obj(&text, &name)
}

/// Parses OBJ text; `name` is used in error messages.
pub fn parse_obj(text: &str, name: &str) -> Result<TriangleMesh, MeshError> {
    let mut mesh = TriangleMesh::default();
    for (number, line) in text.lines().enumerate() {
        let syntax = |message: String| MeshError::Syntax { path: name.to_owned(), line: number + 1, message };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let coordinates: Vec<f32> = words
                    .take(3)
                    .map(|w| w.parse::<f32>().map_err(|_| syntax(format!("`{w}` is not a number"))))
                    .collect::<Result<_, _>>()?;
                let [x, y, z] = coordinates[..] else {
                    return Err(syntax("a vertex needs three coordinates".into()));
                };
                let position = Vec3::new(x, y, z);
                if !position.is_finite() {
                    return Err(syntax("vertex coordinates must be finite".into()));
                }
                mesh.positions.push(position);
            }
            Some("f") => {
                let corners: Vec<u32> = words
                    .map(|w| {
                        obj_index(w, mesh.positions.len()).ok_or_else(|| syntax(format!("bad vertex reference `{w}`")))
                    })
                    .collect::<Result<_, _>>()?;
                if corners.len() < 3 {
                    return Err(syntax("a face needs at least three vertices".into()));
                }
                for k in 1..corners.len() - 1 {
                    mesh.triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(mesh)
}

/// Resolves an OBJ vertex reference (1-based, or negative from the end) to a 0-based index.
fn obj_index(word: &str, vertex_count: usize) -> Option<u32> {
    let index: i64 = word.split('/').next()?.parse().ok()?;
    let resolved = if index > 0 { index - 1 } else { vertex_count as i64 + index };
    (0..vertex_count as i64).contains(&resolved).then_some(resolved as u32)
}

/// Builds a cloth from `mesh` placed by `placement`. Vertices on no face are dropped; the
/// layout then maps the file's vertex numbers to particles (`u32::MAX` for dropped ones).
/// Refuses meshes without faces and faces of zero area, which would carry no mass.
pub fn build_from_mesh(
    mesh: &TriangleMesh,
    placement: Affine3A,
    material: &ClothMaterial,
    name: &str,
) -> Result<ClothData, MeshError> {
    let invalid = |message: String| MeshError::Invalid { path: name.to_owned(), message };
    if mesh.triangles.is_empty() {
        return Err(invalid("the mesh has no faces".into()));
    }
    // Keep only the vertices faces use, in their original order.
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    for tri in &mesh.triangles {
        for &p in tri {
            remap[p as usize] = 0;
        }
    }
    let mut positions = Vec::new();
    for (old, slot) in remap.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = positions.len() as u32;
            positions.push(placement.transform_point3(mesh.positions[old]));
        }
    }
    let triangles: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.map(|p| remap[p as usize])).collect();
    let dropped = positions.len() < mesh.positions.len();
    for (index, tri) in triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|p| positions[p as usize]);
        if triangle_area(a, b, c) <= 1e-12 {
            return Err(invalid(format!("face {} has zero area; remove it or fix its vertices", index + 1)));
        }
    }

    let mut springs = Springs::default();
    let mut add = |i: u32, j: u32, coefficients: Option<SpringCoefficients>, kind| {
        if let Some(c) = coefficients {
            let rest = (positions[i as usize] - positions[j as usize]).length();
            springs.push([i, j], rest, c.stiffness, c.damping, kind);
        }
    };
    let mut edges: Vec<[u32; 2]> =
        triangles.iter().flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]]).map(|[i, j]| [i.min(j), i.max(j)]).collect();
    edges.sort_unstable();
    edges.dedup();
    for &[i, j] in &edges {
        add(i, j, material.stretch, SpringKind::Structural);
    }
    release(edges);
    let interior = interior_edges(&triangles);
    for edge in &interior {
        add(edge.o1, edge.o2, material.bend, SpringKind::Bend);
    }
    release(interior);

    let masses = lumped_masses(&positions, &triangles, material.density);
    Ok(ClothData {
        particles: Particles::at_rest(positions, masses),
        springs,
        triangles: Triangles { indices: triangles },
        hinges: BendingHinges::default(),
        membranes: MembraneTriangles::default(),
        layout: ParticleLayout { grid: None, renumbered: if dropped { remap } else { Vec::new() } },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: &str = "# a unit square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nf 1/1 2/2 3/3\nf 1 3 -2\n";

    fn material() -> ClothMaterial {
        let c = Some(SpringCoefficients { stiffness: 10.0, damping: 0.0 });
        ClothMaterial { density: 2.0, stretch: c, shear: c, bend: c, membrane: None, bending: None }
    }

    #[test]
    fn a_square_of_two_triangles_has_five_edges_and_one_bend_spring() {
        let mesh = parse_obj(SQUARE, "square.obj").expect("valid OBJ");
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let cloth = build_from_mesh(&mesh, Affine3A::IDENTITY, &material(), "square.obj").expect("valid mesh");
        assert_eq!(cloth.particles.len(), 4, "the unused vertex is dropped");
        let bends: Vec<_> =
            cloth.springs.pairs.iter().zip(&cloth.springs.kind).filter(|(_, k)| **k == SpringKind::Bend).collect();
        assert_eq!(cloth.springs.len(), 6);
        assert_eq!(bends.len(), 1);
        assert_eq!(*bends[0].0, [1, 3]);
        assert_eq!(cloth.springs.kind.iter().filter(|k| **k == SpringKind::Structural).count(), 5);
        assert!((cloth.particles.total_mass() - 2.0).abs() < 1e-6);
    }

    #[test]
    fn errors_name_the_line_or_the_face() {
        let err = parse_obj("v 0 0\n", "bad.obj").expect_err("two coordinates");
        assert_eq!(err.to_string(), "bad.obj:1: a vertex needs three coordinates");
        let err = parse_obj("v 0 0 0\nf 1 2 3\n", "bad.obj").expect_err("missing vertices");
        assert!(err.to_string().contains("bad.obj:2: bad vertex reference `2`"));
        let flat = parse_obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "flat.obj").expect("parses");
        let err = build_from_mesh(&flat, Affine3A::IDENTITY, &material(), "flat.obj").expect_err("zero area");
        assert!(err.to_string().contains("face 1 has zero area"));
    }
}
