//! Built-in scenes: Cornell boxes (empty, with two spheres, with a large
//! procedural mesh) and the procedural mesh itself, for BVH work.

use std::f32::consts::TAU;

use glam::Vec3;

use crate::camera::CameraPose;
use crate::error::{Error, Result};
use crate::lights::Light;
use crate::materials::Material;
use crate::math::Rgb;
use crate::scene::{Scene, SceneView};
use crate::shapes::{MaterialId, Sphere, TriangleMesh};
use crate::spectrum::Emission;

/// Names accepted by [`builtin_scene`].
pub const BUILTIN_SCENES: [&str; 3] = ["cornell-spheres", "cornell-empty", "cornell-mesh"];

/// Triangles in `cornell-mesh` unless asked otherwise.
pub const DEFAULT_MESH_TRIANGLES: usize = 1_000_000;

/// A built-in scene by name; `mesh_triangles` sizes `cornell-mesh`.
pub fn builtin_scene(name: &str, mesh_triangles: usize) -> Result<Scene> {
    match name {
        "cornell-empty" => Ok(cornell_box()),
        "cornell-spheres" => {
            let mut scene = cornell_box();
            let white = add_material(
                &mut scene,
                Material::Diffuse {
                    reflectance: Rgb::splat(0.75),
                },
            );
            scene.spheres.push(Sphere {
                center: Vec3::new(-0.42, 0.33, -0.3),
                radius: 0.33,
                material: white,
                emission: None,
            });
            let near = Sphere {
                center: Vec3::new(0.45, 0.33, 0.25),
                radius: 0.33,
                material: white,
                emission: None,
            };
            scene.spheres.push(near.clone());
            // Focus on the nearer sphere's front.
            if let Some(view) = &mut scene.view {
                let (eye, axis) = (
                    view.pose.render_from_camera.translation,
                    view.pose.render_from_camera.z_axis,
                );
                view.focus_distance = (near.center - Vec3::from(eye)).dot(Vec3::from(axis)) - near.radius;
            }
            Ok(scene)
        }
        "cornell-mesh" => {
            let mut scene = cornell_box();
            // Rough copper (RGB complex IOR at 650/550/450 nm, pbrt's Cu data).
            let copper = add_material(
                &mut scene,
                Material::Conductor {
                    eta: Rgb::new(0.200, 0.924, 1.102),
                    k: Rgb::new(3.912, 2.452, 2.142),
                    alpha: 0.2,
                },
            );
            let mut knot = torus_knot(mesh_triangles)?;
            for p in &mut knot.positions {
                *p = *p * 0.2 + Vec3::new(0.0, 0.8, 0.0);
            }
            knot.material = copper;
            scene.meshes.push(knot);
            Ok(scene)
        }
        _ => Err(Error::InvalidArgument(format!(
            "unknown scene '{name}'; built-in scenes are {}",
            BUILTIN_SCENES.join(", ")
        ))),
    }
}

fn add_material(scene: &mut Scene, m: Material) -> MaterialId {
    scene.materials.push(m);
    scene.materials.len() as MaterialId - 1
}

/// A quad `a b c d` (counter-clockwise seen from the front) as a mesh.
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: MaterialId, emission: Option<Rgb>) -> TriangleMesh {
    TriangleMesh {
        positions: vec![a, b, c, d],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material,
        emission: emission.map(Emission::from),
        ..Default::default()
    }
}

/// The box: 2 wide, 2 high, 2 deep, open toward the camera at +z; red wall
/// on the left, blue on the right, and a small square light under the ceiling.
fn cornell_box() -> Scene {
    let mut scene = Scene::default();
    let white = add_material(
        &mut scene,
        Material::Diffuse {
            reflectance: Rgb::new(0.73, 0.73, 0.73),
        },
    );
    let red = add_material(
        &mut scene,
        Material::Diffuse {
            reflectance: Rgb::new(0.63, 0.065, 0.05),
        },
    );
    let blue = add_material(
        &mut scene,
        Material::Diffuse {
            reflectance: Rgb::new(0.08, 0.16, 0.62),
        },
    );
    let v = |x, y, z| Vec3::new(x, y, z);
    // Each wall faces into the box.
    scene.meshes.push(quad(
        v(-1., 0., 1.),
        v(1., 0., 1.),
        v(1., 0., -1.),
        v(-1., 0., -1.),
        white,
        None,
    )); // floor
    scene.meshes.push(quad(
        v(-1., 2., -1.),
        v(1., 2., -1.),
        v(1., 2., 1.),
        v(-1., 2., 1.),
        white,
        None,
    )); // ceiling
    scene.meshes.push(quad(
        v(-1., 0., -1.),
        v(1., 0., -1.),
        v(1., 2., -1.),
        v(-1., 2., -1.),
        white,
        None,
    )); // back
    scene.meshes.push(quad(
        v(-1., 0., 1.),
        v(-1., 0., -1.),
        v(-1., 2., -1.),
        v(-1., 2., 1.),
        red,
        None,
    )); // left
    scene.meshes.push(quad(
        v(1., 0., -1.),
        v(1., 0., 1.),
        v(1., 2., 1.),
        v(1., 2., -1.),
        blue,
        None,
    )); // right
    let (s, y) = (0.25, 1.98);
    scene.meshes.push(quad(
        v(-s, y, -s),
        v(s, y, -s),
        v(s, y, s),
        v(-s, y, s),
        white,
        Some(Rgb::new(15.0, 12.5, 9.0)),
    ));
    // Framed for a 50 mm lens on a 36 mm wide sensor at 4:3 (about 29° vertically).
    scene.view = Some(SceneView {
        pose: CameraPose::look_at(v(0.0, 1.0, 3.85), v(0.0, 0.92, 0.0), Vec3::Y),
        fov_y_deg: 29.0,
        focus_distance: 3.85,
    });
    scene
}

/// Test charts: an empty scene with two diffuse materials, white (0.8, id 0)
/// and dark (0.1, id 1), under a white sky of radiance 1. Add boards to it
/// with [`add_checkerboard`].
pub fn checker_scene() -> Scene {
    Scene {
        materials: vec![
            Material::Diffuse {
                reflectance: Rgb::splat(0.8),
            },
            Material::Diffuse {
                reflectance: Rgb::splat(0.1),
            },
        ],
        lights: vec![Light::Environment {
            radiance: Rgb::ONE.into(),
        }],
        ..Default::default()
    }
}

/// Adds checker squares of `size` scene units, alternating materials 0 and
/// 1, over [x0, x1] × [y0, y1] of the plane z = −`distance`, facing +z.
pub fn add_checkerboard(scene: &mut Scene, (x0, x1): (f32, f32), (y0, y1): (f32, f32), distance: f32, size: f32) {
    let (nx, ny) = (((x1 - x0) / size).ceil() as i32, ((y1 - y0) / size).ceil() as i32);
    let z = -distance;
    for j in 0..ny {
        for i in 0..nx {
            let (xa, ya) = (x0 + i as f32 * size, y0 + j as f32 * size);
            let (xb, yb) = ((xa + size).min(x1), (ya + size).min(y1));
            scene.meshes.push(quad(
                Vec3::new(xa, ya, z),
                Vec3::new(xb, ya, z),
                Vec3::new(xb, yb, z),
                Vec3::new(xa, yb, z),
                ((i + j) % 2) as MaterialId,
                None,
            ));
        }
    }
}

/// A closed (3, 7) torus knot tube with a rippled surface, about
/// `triangles` triangles (at least 512), centred at the origin, radius about 3.
pub fn torus_knot(triangles: usize) -> Result<TriangleMesh> {
    if !(512..=200_000_000).contains(&triangles) {
        return Err(Error::InvalidArgument(format!(
            "procedural mesh needs 512 to 200000000 triangles, got {triangles}"
        )));
    }
    // 2·U·V triangles with U = 8·V segments along the knot.
    let around = ((triangles as f64 / 16.0).sqrt().round() as usize).max(8);
    let along = (triangles / (2 * around)).max(8);
    let (p, q) = (3.0f32, 7.0f32);
    let curve = |t: f32| {
        let r = 2.0 + 0.8 * (q * t).cos();
        Vec3::new(r * (p * t).cos(), r * (p * t).sin(), 0.8 * (q * t).sin())
    };
    let tube = 0.28f32;
    let mut positions = Vec::with_capacity(along * around);
    for i in 0..along {
        let t = i as f32 / along as f32 * TAU;
        let h = 1e-3;
        let (c0, c1, c2) = (curve(t - h), curve(t), curve(t + h));
        let tangent = (c2 - c0).normalize();
        let normal = (c2 - 2.0 * c1 + c0).reject_from(tangent).normalize();
        let binormal = tangent.cross(normal);
        for j in 0..around {
            let a = j as f32 / around as f32 * TAU;
            let ripple = 1.0 + 0.12 * (5.0 * a + 40.0 * t).sin() * (3.0 * t).cos();
            positions.push(c1 + tube * ripple * (a.cos() * normal + a.sin() * binormal));
        }
    }
    let mut indices = Vec::with_capacity(2 * along * around);
    let id = |i: usize, j: usize| ((i % along) * around + (j % around)) as u32;
    for i in 0..along {
        for j in 0..around {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            indices.push([a, b, c]);
            indices.push([a, c, d]);
        }
    }
    Ok(TriangleMesh {
        positions,
        indices,
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_scenes_are_valid() {
        for name in BUILTIN_SCENES {
            let scene = builtin_scene(name, 20_000).unwrap();
            scene.validate().unwrap();
            assert!(scene.view.is_some());
        }
        assert!(builtin_scene("cornell-nope", 0).is_err());
    }

    #[test]
    fn torus_knot_has_the_requested_size_and_is_closed() {
        let mesh = torus_knot(1_000_000).unwrap();
        let n = mesh.indices.len();
        assert!((1_000_000..1_010_000).contains(&n), "{n} triangles");
        // Closed surface: every edge is shared by exactly two triangles, so
        // the signed volume is the same whichever way it is computed.
        let small = torus_knot(5000).unwrap();
        let mut edges = std::collections::HashMap::new();
        for t in &small.indices {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2));
    }
}
