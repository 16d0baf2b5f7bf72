//! PLY meshes (Turk 1994; ASCII and binary of either endianness, read with
//! ply-rs-bw): vertex positions, vertex normals when present, polygon faces
//! (fan-triangulated). Also a binary PLY writer, so other renderers can be run
//! on exactly lenspath's triangles.

use std::io::{BufRead, BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{Encoding, Header, Property, PropertyAccess, PropertyType, ScalarType};

use super::import::{MeshBuilder, Warnings};
use crate::error::{Error, Result};
use crate::fs::{io_error, write_atomically};
use crate::shapes::TriangleMesh;

#[derive(Default)]
struct PlyVertex {
    position: [f32; 3],
    normal: [f32; 3],
}

fn scalar(property: Property) -> f32 {
    match property {
        Property::Float(v) => v,
        Property::Double(v) => v as f32,
        Property::Int(v) => v as f32,
        Property::UInt(v) => v as f32,
        Property::Short(v) => v as f32,
        Property::UShort(v) => v as f32,
        Property::Char(v) => v as f32,
        Property::UChar(v) => v as f32,
        _ => f32::NAN,
    }
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        let slot = match name {
            "x" => &mut self.position[0],
            "y" => &mut self.position[1],
            "z" => &mut self.position[2],
            "nx" => &mut self.normal[0],
            "ny" => &mut self.normal[1],
            "nz" => &mut self.normal[2],
            _ => return,
        };
        *slot = scalar(property);
    }
}

/// A face's vertex indices as the file wrote them (signed, so a negative or
/// over-large index is reported as written); `None` when they were not
/// integers.
#[derive(Default)]
struct PlyFace(Option<Vec<i64>>);

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_property(&mut self, name: &str, property: Property) {
        if name != "vertex_indices" && name != "vertex_index" {
            return;
        }
        self.0 = match property {
            Property::ListInt(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUInt(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUShort(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListChar(v) => Some(v.into_iter().map(i64::from).collect()),
            Property::ListUChar(v) => Some(v.into_iter().map(i64::from).collect()),
            _ => None,
        };
    }
}

fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// Fails fast when the header's element counts need more bytes than follow it
/// (a truncated file, or a corrupt count such as 10^12 faces).
fn check_counts(header: &Header, payload_bytes: u64, fail: &dyn Fn(String) -> Error) -> Result<()> {
    let mut needed: u64 = 0;
    for (name, element) in &header.elements {
        let per_element: u64 = element
            .properties
            .values()
            .map(|p| match header.encoding {
                // At least one digit and one separator per value.
                Encoding::Ascii => 2,
                _ => match &p.data_type {
                    PropertyType::Scalar(t) => scalar_bytes(t),
                    PropertyType::List(count, _) => scalar_bytes(count),
                },
            })
            .sum();
        let bytes = (element.count as u64).saturating_mul(per_element.max(1));
        needed = needed.saturating_add(bytes);
        if needed > payload_bytes {
            return Err(fail(format!(
                "the header declares {} '{name}' elements, which need at least {bytes} bytes, but only {payload_bytes} bytes follow the header (truncated file or corrupt count)",
                element.count
            )));
        }
    }
    Ok(())
}

/// Reads a PLY mesh: positions, normals (`nx ny nz`) when every vertex has them, faces.
pub fn load_ply(path: &Path, warnings: &mut Warnings) -> Result<TriangleMesh> {
    let file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let size = file.metadata().map_err(|e| io_error(path, e))?.len();
    let mut reader = BufReader::with_capacity(1 << 20, file);
    read_ply(&mut reader, size, path, warnings)
}

/// Parses PLY bytes; `path` names the file in messages.
pub fn parse_ply(bytes: &[u8], path: &Path, warnings: &mut Warnings) -> Result<TriangleMesh> {
    read_ply(&mut std::io::Cursor::new(bytes), bytes.len() as u64, path, warnings)
}

fn read_ply<R: BufRead + Seek>(
    reader: &mut R,
    size: u64,
    path: &Path,
    warnings: &mut Warnings,
) -> Result<TriangleMesh> {
    // ply-rs-bw's messages span lines; keep ours to one.
    let fail = |m: String| Error::Parse {
        kind: crate::FileKind::Scene,
        path: path.to_path_buf(),
        message: m.split_whitespace().collect::<Vec<_>>().join(" "),
    };
    let vertex_parser = Parser::<PlyVertex>::new();
    let face_parser = Parser::<PlyFace>::new();
    let header = vertex_parser
        .read_header(reader)
        .map_err(|e| fail(format!("bad header: {e}")))?;
    let header_bytes = reader.stream_position().map_err(|e| io_error(path, e))?;
    check_counts(&header, size.saturating_sub(header_bytes), &fail)?;

    let mut builder = MeshBuilder::default();
    let mut faces = Vec::new();
    for (name, element) in &header.elements {
        match name.as_str() {
            "vertex" => {
                for axis in ["x", "y", "z"] {
                    if !element.properties.contains_key(axis) {
                        return Err(fail(format!("element 'vertex' has no property '{axis}'")));
                    }
                }
                let has_normals = ["nx", "ny", "nz"].iter().all(|n| element.properties.contains_key(*n));
                let vs = vertex_parser
                    .read_payload_for_element(reader, element, &header)
                    .map_err(|e| fail(format!("bad vertex data: {e}")))?;
                if let Some(i) = vs.iter().position(|v| !v.position.iter().all(|c| c.is_finite())) {
                    return Err(fail(format!("vertex {i} has a coordinate that is not a finite number")));
                }
                builder.mesh.positions = vs.iter().map(|v| Vec3::from_array(v.position)).collect();
                if has_normals {
                    builder.mesh.normals = Some(
                        vs.iter()
                            .map(|v| Vec3::from_array(v.normal).normalize_or_zero())
                            .collect(),
                    );
                }
            }
            "face" => {
                faces = face_parser
                    .read_payload_for_element(reader, element, &header)
                    .map_err(|e| fail(format!("bad face data: {e}")))?;
            }
            other => {
                // Other elements (edges, materials, ...) must still be read past.
                face_parser
                    .read_payload_for_element(reader, element, &header)
                    .map_err(|e| fail(format!("bad '{other}' data: {e}")))?;
            }
        }
    }
    check_nothing_follows(reader, &header, &fail)?;
    let n = builder.mesh.positions.len();
    let mut corners = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let Some(indices) = &face.0 else {
            return Err(fail(format!("face {f}'s vertex indices are not integers")));
        };
        if let Some(&v) = indices.iter().find(|&&v| !(0..n as i64).contains(&v)) {
            return Err(fail(format!(
                "face {f} refers to vertex {v} but there are {n} vertices"
            )));
        }
        corners.clear();
        corners.extend(indices.iter().map(|&v| v as u32));
        builder.polygon(&corners);
    }
    let name = path.display().to_string();
    let mesh = builder.finish(&name, warnings);
    if mesh.indices.is_empty() {
        return Err(fail("no faces with area: nothing to render".into()));
    }
    Ok(mesh)
}

/// Fails if data follows the elements the header declares (beyond
/// whitespace): a header that declares fewer elements than the file holds
/// would otherwise drop the rest silently.
fn check_nothing_follows<R: BufRead>(reader: &mut R, header: &Header, fail: &dyn Fn(String) -> Error) -> Result<()> {
    let mut rest = Vec::new();
    reader
        .take(1 << 16)
        .read_to_end(&mut rest)
        .map_err(|e| fail(format!("cannot read past the elements: {e}")))?;
    if rest.iter().all(u8::is_ascii_whitespace) {
        return Ok(());
    }
    let declared: Vec<String> = header
        .elements
        .iter()
        .map(|(name, e)| format!("{} '{name}'", e.count))
        .collect();
    Err(fail(format!(
        "data follows the {} elements the header declares: it declares fewer than the file holds",
        declared.join(" and ")
    )))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &[u8]) -> Result<(TriangleMesh, Warnings)> {
        let mut warnings = Warnings::default();
        parse_ply(text, Path::new("test.ply"), &mut warnings).map(|m| (m, warnings))
    }

    #[test]
    fn written_ply_reads_back_identically() {
        let mesh = crate::builtin::torus_knot(2_000).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("knot.ply");
        write_ply(&path, &mesh).unwrap();
        let back = load_ply(&path, &mut Warnings::default()).unwrap();
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

    /// The same quad in ASCII, binary little- and big-endian: same mesh, with
    /// normals, the quad split into two triangles.
    #[test]
    fn ascii_and_both_binary_encodings_agree() {
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                 property float nx\nproperty float ny\nproperty float nz\n\
                 element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            )
        };
        let verts = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let mut ascii = header("ascii");
        for v in verts {
            ascii += &format!("{} {} {} 0 0 1\n", v[0], v[1], v[2]);
        }
        ascii += "4 0 1 2 3\n";
        let binary = |big: bool| {
            let mut b = header(if big {
                "binary_big_endian"
            } else {
                "binary_little_endian"
            })
            .into_bytes();
            let mut put = |x: f32| b.extend(if big { x.to_be_bytes() } else { x.to_le_bytes() });
            for v in verts {
                for c in v.into_iter().chain([0.0, 0.0, 1.0]) {
                    put(c);
                }
            }
            b.push(4);
            for i in 0..4i32 {
                b.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
            }
            b
        };
        let (a, _) = parse(ascii.as_bytes()).unwrap();
        assert_eq!(a.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(a.normals.as_ref().unwrap()[2], Vec3::Z);
        for big in [false, true] {
            let (b, _) = parse(&binary(big)).unwrap();
            assert_eq!(b.positions, a.positions);
            assert_eq!(b.indices, a.indices);
            assert_eq!(b.normals, a.normals);
        }
    }

    #[test]
    fn absurd_face_count_fails_fast_with_a_clear_message() {
        let text = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1000000000000\nproperty list uchar int vertex_indices\nend_header\n";
        let mut bytes = text.to_vec();
        bytes.extend([0u8; 36 + 13]); // three vertices and one face
        let err = parse(&bytes).unwrap_err().to_string();
        assert!(err.contains("1000000000000 'face' elements"), "{err}");
    }

    #[test]
    fn degenerate_faces_are_skipped_and_counted() {
        let text = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n2 0 0\n3 0 1 2\n3 0 0 1\n3 0 1 3\n";
        let (mesh, warnings) = parse(text).unwrap();
        assert_eq!(mesh.indices.len(), 1);
        assert_eq!(warnings.iter().next().unwrap().1, 2);
    }
}
