//! Triangle meshes from PLY (ASCII and binary, via ply-rs-bw) and OBJ (via tobj),
//! and to binary PLY (for running other renderers on the same triangles).
//! Polygons are fan-triangulated. Full scene import (materials, COLLADA,
//! glTF) lives elsewhere; this reads geometry.

use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{Property, PropertyAccess};

use super::{io_error, write_atomically};
use crate::error::{Error, Result};
use crate::shapes::TriangleMesh;

/// Loads the geometry of a `.ply` or `.obj` file as one mesh (material 0, no emission).
pub fn load_mesh(path: &Path) -> Result<TriangleMesh> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let mesh = match ext.as_deref() {
        Some("ply") => load_ply(path)?,
        Some("obj") => load_obj(path)?,
        _ => {
            return Err(Error::InvalidArgument(format!(
                "{}: unknown mesh extension; use .ply or .obj",
                path.display()
            )))
        }
    };
    let fail = |m: String| Error::Parse {
        path: path.to_path_buf(),
        message: m,
    };
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(fail(format!("vertex {i} has a non-finite coordinate")));
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.indices.iter().position(|t| t.iter().any(|&v| v >= n)) {
        return Err(fail(format!("face {t} refers to a vertex beyond the {n} vertices")));
    }
    if mesh.indices.is_empty() {
        return Err(fail("no triangles".into()));
    }
    Ok(mesh)
}

#[derive(Default)]
struct PlyVertex([f32; 3]);

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return,
        };
        self.0[axis] = match property {
            Property::Float(v) => v,
            Property::Double(v) => v as f32,
            Property::Int(v) => v as f32,
            Property::UInt(v) => v as f32,
            Property::Short(v) => v as f32,
            Property::UShort(v) => v as f32,
            Property::Char(v) => v as f32,
            Property::UChar(v) => v as f32,
            _ => f32::NAN,
        };
    }
}

#[derive(Default)]
struct PlyFace(Vec<u32>);

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        if name != "vertex_indices" && name != "vertex_index" {
            return;
        }
        self.0 = match property {
            Property::ListInt(v) => v.iter().map(|&i| i as u32).collect(),
            Property::ListUInt(v) => v,
            Property::ListShort(v) => v.iter().map(|&i| i as u32).collect(),
            Property::ListUShort(v) => v.iter().map(|&i| u32::from(i)).collect(),
            Property::ListChar(v) => v.iter().map(|&i| i as u32).collect(),
            Property::ListUChar(v) => v.iter().map(|&i| u32::from(i)).collect(),
            _ => Vec::new(),
        };
    }
}

fn load_ply(path: &Path) -> Result<TriangleMesh> {
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let fail = |m: String| Error::Parse {
        path: path.to_path_buf(),
        message: m,
    };
    let mut reader = BufReader::new(file);
    let vertex_parser = Parser::<PlyVertex>::new();
    let face_parser = Parser::<PlyFace>::new();
    let header = vertex_parser
        .read_header(&mut reader)
        .map_err(|e| fail(format!("bad header: {e}")))?;
    let mut mesh = TriangleMesh::default();
    for (name, element) in &header.elements {
        match name.as_str() {
            "vertex" => {
                let vs = vertex_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| fail(format!("bad vertex data: {e}")))?;
                mesh.positions = vs.into_iter().map(|v| Vec3::from_array(v.0)).collect();
            }
            "face" => {
                let fs = face_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| fail(format!("bad face data: {e}")))?;
                for f in fs {
                    for k in 1..f.0.len().saturating_sub(1) {
                        mesh.indices.push([f.0[0], f.0[k], f.0[k + 1]]);
                    }
                }
            }
            other => {
                // Elements before the faces must still be read past.
                face_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| fail(format!("bad '{other}' data: {e}")))?;
            }
        }
    }
    Ok(mesh)
}

/// Writes the mesh's positions and triangles as binary little-endian PLY
/// (float x y z; uchar-counted int vertex_indices), atomically.
pub fn write_ply(path: &Path, mesh: &TriangleMesh) -> Result<()> {
    write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| io_error(path, e))?;
        let mut out = BufWriter::new(file);
        let header = format!(
            "ply\nformat binary_little_endian 1.0\ncomment written by lenspath\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar int vertex_indices\nend_header\n",
            mesh.positions.len(),
            mesh.indices.len()
        );
        let mut bytes = header.into_bytes();
        bytes.reserve(12 * mesh.positions.len() + 13 * mesh.indices.len());
        for p in &mesh.positions {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in &mesh.indices {
            bytes.push(3);
            for &v in t {
                bytes.extend_from_slice(&(v as i32).to_le_bytes());
            }
        }
        out.write_all(&bytes)
            .and_then(|()| out.flush())
            .map_err(|e| io_error(path, e))
    })
}

fn load_obj(path: &Path) -> Result<TriangleMesh> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &options).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut mesh = TriangleMesh::default();
    for model in models {
        let base = mesh.positions.len() as u32;
        let m = model.mesh;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_ply_reads_back_identically() {
        let mesh = crate::builtin::torus_knot(2_000).unwrap();
        let dir = std::env::temp_dir().join(format!("lenspath-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("knot.ply");
        write_ply(&path, &mesh).unwrap();
        let back = load_mesh(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(back.positions, mesh.positions);
        assert_eq!(back.indices, mesh.indices);
    }

    #[test]
    fn unwritable_ply_path_is_an_io_error_naming_it() {
        let mesh = crate::builtin::torus_knot(2_000).unwrap();
        let path = Path::new("/nonexistent-dir/knot.ply");
        let err = write_ply(path, &mesh).unwrap_err();
        assert!(err.to_string().contains("/nonexistent-dir/knot.ply"), "{err}");
    }
}
