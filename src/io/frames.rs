//! Frame meshes: OBJ with vertex normals, or binary PLY.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::write_atomically;
use crate::scene::format::FrameFormat;
use crate::simulation::ClothSurface;

/// File name of frame `frame` in `format`: `frame_NNNN.obj` or `.ply`.
pub fn frame_file_name(frame: u64, format: FrameFormat) -> String {
    let extension = match format {
        FrameFormat::Obj => "obj",
        FrameFormat::Ply => "ply",
    };
    format!("frame_{frame:04}.{extension}")
}

/// Writes all cloths of one frame into `dir` in each of `formats`; returns the paths.
pub fn write_frame(
    dir: &Path,
    frame: u64,
    formats: &[FrameFormat],
    surfaces: &[ClothSurface<'_>],
) -> std::io::Result<Vec<PathBuf>> {
    formats
        .iter()
        .map(|&format| {
            let path = dir.join(frame_file_name(frame, format));
            write_atomically(&path, |out| match format {
                FrameFormat::Obj => write_obj(out, surfaces),
                FrameFormat::Ply => write_ply(out, surfaces),
            })?;
            Ok(path)
        })
        .collect()
}

/// Writes the surfaces as one OBJ file with one object per cloth.
pub fn write_obj(out: &mut dyn Write, surfaces: &[ClothSurface<'_>]) -> std::io::Result<()> {
    writeln!(out, "# selvedge frame")?;
    let mut offset = 1;
    for surface in surfaces {
        writeln!(out, "o {}", surface.name)?;
        for p in surface.positions {
            writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
        }
        for n in surface.normals {
            writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
        }
        for t in surface.triangles {
            let [a, b, c] = t.map(|i| i as usize + offset);
            writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
        offset += surface.positions.len();
    }
    Ok(())
}

/// Writes the surfaces merged into one binary little-endian PLY mesh with normals.
pub fn write_ply(out: &mut dyn Write, surfaces: &[ClothSurface<'_>]) -> std::io::Result<()> {
    let vertices: usize = surfaces.iter().map(|s| s.positions.len()).sum();
    let faces: usize = surfaces.iter().map(|s| s.triangles.len()).sum();
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment selvedge frame\nelement vertex {vertices}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         element face {faces}\nproperty list uchar uint vertex_indices\nend_header\n"
    )?;
    for surface in surfaces {
        for (p, n) in surface.positions.iter().zip(surface.normals) {
            for value in [p.x, p.y, p.z, n.x, n.y, n.z] {
                out.write_all(&value.to_le_bytes())?;
            }
        }
    }
    let mut offset = 0u32;
    for surface in surfaces {
        for t in surface.triangles {
            out.write_all(&[3])?;
            for i in t {
                out.write_all(&(i + offset).to_le_bytes())?;
            }
        }
        offset += surface.positions.len() as u32;
    }
    Ok(())
}
