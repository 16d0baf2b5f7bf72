//! Scenes: the description a user or loader fills in ([`Scene`]), and the
//! compiled form the integrator traces ([`CompiledScene`]): a BVH over
//! every primitive plus the area lights made from emissive shapes.

use glam::Vec3;

use crate::accel::{Bvh, BvhSettings, PrimGeometry};
use crate::camera::CameraPose;
use crate::error::{Error, Result};
use crate::lights::{AreaLight, Light};
use crate::materials::{Material, SpectralMaterial};
use crate::math::{within_scene_range, Bounds3, Rgb, MAX_SCENE_COORDINATE};
use crate::ray::Ray;
use crate::shapes::{MaterialId, Sphere, TriangleMesh};
use crate::spectrum::{Emission, Spectrum};

/// The camera placement and field of view a scene suggests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneView {
    /// Where the camera is and where it looks.
    pub pose: CameraPose,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    /// Distance to the subject, a sensible default focus distance (scene units).
    pub focus_distance: f32,
}

/// A scene description: shapes, materials, lights and a suggested view.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Triangle meshes.
    pub meshes: Vec<TriangleMesh>,
    /// Analytic spheres.
    pub spheres: Vec<Sphere>,
    /// Materials, indexed by the shapes' `material`.
    pub materials: Vec<Material>,
    /// Point, directional and environment lights (area lights come from emissive shapes).
    pub lights: Vec<Light>,
    /// The view the scene was made for.
    pub view: Option<SceneView>,
}

/// Which shape a BVH primitive belongs to (its [`PrimGeometry`] says
/// whether it is a triangle or a sphere).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimRef {
    /// Index of its mesh, or of the sphere.
    pub shape: u32,
    /// Triangle index in the mesh (0 for a sphere).
    pub triangle: u32,
}

/// Everything the integrator needs about a ray's closest hit.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// Distance along the ray (unit direction: scene units).
    pub t: f32,
    /// Hit point.
    pub p: Vec3,
    /// Unit geometric normal (front face: counter-clockwise winding, sphere outside).
    pub geometric_normal: Vec3,
    /// Unit shading normal, on the same side as the geometric normal.
    pub shading_normal: Vec3,
    /// Material of the surface.
    pub material: MaterialId,
    /// Area light index when the surface emits.
    pub area_light: Option<u32>,
}

/// A scene ready to be traced.
pub struct CompiledScene {
    scene: Scene,
    bvh: Bvh<PrimRef>,
    /// Each material's spectra, by `MaterialId`.
    materials: Vec<SpectralMaterial>,
    /// Each of `scene.lights`' emission spectrum.
    light_emission: Vec<Spectrum>,
    area_lights: Vec<AreaLight>,
    mesh_light: Vec<Option<u32>>,
    sphere_light: Vec<Option<u32>>,
}

fn check_rgb(what: &str, c: Rgb) -> Result<()> {
    if !c.is_finite() || c.min_element() < 0.0 {
        return Err(Error::InvalidScene(format!(
            "{what} must be finite and non-negative, got {c}"
        )));
    }
    Ok(())
}

/// An RGB emission must be finite and non-negative (a spectral one was
/// checked when it was made).
fn check_emission(what: &str, e: &Emission) -> Result<()> {
    match e {
        Emission::Rgb(c) => check_rgb(what, *c),
        Emission::Spectral(_) => Ok(()),
    }
}

/// A microfacet roughness must be finite and non-negative.
fn check_alpha(material: usize, alpha: f32) -> Result<()> {
    if !(alpha >= 0.0 && alpha.is_finite()) {
        return Err(Error::InvalidScene(format!(
            "material {material}: alpha must be ≥ 0, got {alpha}"
        )));
    }
    Ok(())
}

impl Scene {
    /// Total number of triangles in all meshes.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    /// Meshes and spheres that emit light (area lights).
    pub fn emitter_count(&self) -> usize {
        self.meshes.iter().filter(|m| m.emission.is_some()).count()
            + self.spheres.iter().filter(|s| s.emission.is_some()).count()
    }

    /// Checks the description for errors a loader or user could make.
    pub fn validate(&self) -> Result<()> {
        let check_material = |what: String, id: MaterialId| {
            if id as usize >= self.materials.len() {
                return Err(Error::InvalidScene(format!(
                    "{what} uses material {id}, but the scene has {} materials",
                    self.materials.len()
                )));
            }
            Ok(())
        };
        for (i, m) in self.meshes.iter().enumerate() {
            check_material(format!("mesh {i}"), m.material)?;
            if let Some(p) = m.positions.iter().position(|&p| !within_scene_range(p)) {
                return Err(Error::InvalidScene(format!(
                    "mesh {i}: vertex {p} {} is not finite or beyond ±{MAX_SCENE_COORDINATE:e} scene units",
                    m.positions[p]
                )));
            }
            let n = m.positions.len() as u32;
            if let Some(t) = m.indices.iter().position(|tri| tri.iter().any(|&v| v >= n)) {
                return Err(Error::InvalidScene(format!(
                    "mesh {i}: triangle {t} indexes a vertex beyond the {n} it has"
                )));
            }
            if m.normals.as_ref().is_some_and(|ns| ns.len() != m.positions.len()) {
                return Err(Error::InvalidScene(format!(
                    "mesh {i}: normal count differs from vertex count"
                )));
            }
            if m.uvs.as_ref().is_some_and(|uv| uv.len() != m.positions.len()) {
                return Err(Error::InvalidScene(format!(
                    "mesh {i}: uv count differs from vertex count"
                )));
            }
            if let Some(e) = &m.emission {
                check_emission(&format!("mesh {i} emission"), e)?;
            }
        }
        for (i, s) in self.spheres.iter().enumerate() {
            check_material(format!("sphere {i}"), s.material)?;
            if !(within_scene_range(s.center) && s.radius > 0.0 && s.radius <= MAX_SCENE_COORDINATE) {
                return Err(Error::InvalidScene(format!(
                    "sphere {i}: centre must be finite and radius positive, both within {MAX_SCENE_COORDINATE:e} scene units, got {} and {}",
                    s.center, s.radius
                )));
            }
            if let Some(e) = &s.emission {
                check_emission(&format!("sphere {i} emission"), e)?;
            }
        }
        for (i, m) in self.materials.iter().enumerate() {
            match *m {
                Material::Diffuse { reflectance } | Material::Mirror { reflectance } => {
                    check_rgb(&format!("material {i} reflectance"), reflectance)?
                }
                Material::Dielectric {
                    eta,
                    reflectance,
                    transmittance,
                } => {
                    let n_d = eta.n_d();
                    if !(n_d > 0.0 && n_d.is_finite()) {
                        return Err(Error::InvalidScene(format!(
                            "material {i}: eta must be positive, got {n_d}"
                        )));
                    }
                    check_rgb(&format!("material {i} reflectance"), reflectance)?;
                    check_rgb(&format!("material {i} transmittance"), transmittance)?;
                }
                Material::MeasuredConductor { alpha, .. } => check_alpha(i, alpha)?,
                Material::Conductor { eta, k, alpha } => {
                    check_rgb(&format!("material {i} eta"), eta)?;
                    check_rgb(&format!("material {i} k"), k)?;
                    check_alpha(i, alpha)?;
                }
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            let (what, value) = match *l {
                Light::Point {
                    ref intensity,
                    position,
                } => {
                    if !position.is_finite() {
                        return Err(Error::InvalidScene(format!("light {i}: position is not finite")));
                    }
                    ("intensity", intensity)
                }
                Light::Spot {
                    position,
                    direction,
                    ref intensity,
                    cos_cutoff,
                    exponent,
                } => {
                    if !position.is_finite() || !direction.is_normalized() {
                        return Err(Error::InvalidScene(format!(
                            "light {i}: spot position must be finite and direction unit length"
                        )));
                    }
                    if !((-1.0..=1.0).contains(&cos_cutoff) && exponent >= 0.0 && exponent.is_finite()) {
                        return Err(Error::InvalidScene(format!(
                            "light {i}: spot cone cosine must be in [-1, 1] and exponent ≥ 0"
                        )));
                    }
                    ("intensity", intensity)
                }
                Light::Directional {
                    ref irradiance,
                    direction,
                } => {
                    if !direction.is_finite() || direction.length_squared() == 0.0 {
                        return Err(Error::InvalidScene(format!("light {i}: direction must be non-zero")));
                    }
                    ("irradiance", irradiance)
                }
                Light::Environment { ref radiance } => ("radiance", radiance),
            };
            check_emission(&format!("light {i} {what}"), value)?;
        }
        Ok(())
    }

    /// [`Scene::compile`] on `threads` worker threads (`None`: every core),
    /// as a render asked for that many runs.
    pub fn compile_on(self, settings: &BvhSettings, threads: Option<usize>) -> Result<CompiledScene> {
        crate::parallel::worker_pool(threads)?.install(|| self.compile(settings))
    }

    /// Validates the scene and builds its acceleration structure and lights.
    /// The BVH is built on the current rayon pool's threads (every core
    /// unless the caller installs a pool); its tree does not depend on how many.
    pub fn compile(self, settings: &BvhSettings) -> Result<CompiledScene> {
        self.validate()?;
        let mut prims = Vec::with_capacity(self.triangle_count() + self.spheres.len());
        for (mi, m) in self.meshes.iter().enumerate() {
            for (ti, tri) in m.triangles().enumerate() {
                // Zero-area triangles can never be hit; leave them out.
                if (tri[1] - tri[0]).cross(tri[2] - tri[0]).length_squared() > 0.0 {
                    prims.push((
                        PrimGeometry::Triangle(tri),
                        PrimRef {
                            shape: mi as u32,
                            triangle: ti as u32,
                        },
                    ));
                }
            }
        }
        for (si, s) in self.spheres.iter().enumerate() {
            prims.push((
                PrimGeometry::Sphere {
                    center: s.center,
                    radius: s.radius,
                },
                PrimRef {
                    shape: si as u32,
                    triangle: 0,
                },
            ));
        }
        let bvh = Bvh::build(prims, settings);

        let mut area_lights = Vec::new();
        let mesh_light = self
            .meshes
            .iter()
            .map(|m| {
                let radiance = m.emission.as_ref().filter(|e| !e.is_black())?;
                let tris = m.triangles().collect();
                let light = AreaLight::from_triangles(tris, radiance.spectrum())?;
                area_lights.push(light);
                Some(area_lights.len() as u32 - 1)
            })
            .collect();
        let sphere_light = self
            .spheres
            .iter()
            .map(|s| {
                let radiance = s.emission.as_ref().filter(|e| !e.is_black())?;
                area_lights.push(AreaLight::from_sphere(s.center, s.radius, radiance.spectrum()));
                Some(area_lights.len() as u32 - 1)
            })
            .collect();
        let materials = self.materials.iter().map(SpectralMaterial::new).collect();
        let light_emission = self.lights.iter().map(|l| l.emission().spectrum()).collect();
        Ok(CompiledScene {
            scene: self,
            bvh,
            materials,
            light_emission,
            area_lights,
            mesh_light,
            sphere_light,
        })
    }
}

impl CompiledScene {
    /// Bounds of all geometry.
    pub fn bounds(&self) -> Bounds3 {
        self.bvh.bounds()
    }

    /// Area lights, indexed by [`SurfaceHit::area_light`].
    pub fn area_lights(&self) -> &[AreaLight] {
        &self.area_lights
    }

    /// Point, directional and environment lights.
    pub fn lights(&self) -> &[Light] {
        &self.scene.lights
    }

    /// [`CompiledScene::lights`] with each one's emission spectrum.
    pub fn lights_with_emission(&self) -> impl Iterator<Item = (&Light, &Spectrum)> {
        self.scene.lights.iter().zip(&self.light_emission)
    }

    /// Every material's spectra, by [`MaterialId`].
    pub fn spectral_materials(&self) -> &[SpectralMaterial] {
        &self.materials
    }

    /// Material `id`'s spectra.
    #[inline(always)]
    pub fn spectral_material(&self, id: MaterialId) -> &SpectralMaterial {
        &self.materials[id as usize]
    }

    /// True when something lies on `ray` within `0 < t < t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.bvh.intersect_any(ray, t_max)
    }

    /// Which of the rays from `origin` to `targets` (at most
    /// [`SHADOW_PACKET`](crate::accel::SHADOW_PACKET)) are blocked within
    /// `0 < t < t_max`, `t` in units of the distance to the target: bit `i`
    /// for `targets[i]`. The same answers as [`CompiledScene::occluded`] on
    /// each ray, traced as one packet.
    #[inline]
    pub fn occluded_from(&self, origin: Vec3, targets: &[Vec3], t_max: f32) -> u32 {
        self.bvh.occluded_from(origin, targets, t_max)
    }

    /// The closest surface hit along `ray` (unit direction).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        let hit = self.bvh.intersect(ray, f32::INFINITY)?;
        let PrimRef { shape, triangle } = self.bvh.tag(hit.prim);
        // The corners and centres from the BVH's leaf packs (the ones just
        // tested, so in the cache), not through the mesh's indices.
        Some(match self.bvh.primitive(hit.prim) {
            PrimGeometry::Triangle([p0, p1, p2]) => {
                let m = &self.scene.meshes[shape as usize];
                let b0 = 1.0 - hit.b1 - hit.b2;
                // Barycentric interpolation is more accurate than origin + t·direction.
                let p = b0 * p0 + hit.b1 * p1 + hit.b2 * p2;
                let geometric_normal = (p1 - p0).cross(p2 - p0).normalize();
                let shading_normal = m
                    .normals
                    .as_ref()
                    .and_then(|ns| {
                        let [i0, i1, i2] = m.indices[triangle as usize].map(|i| i as usize);
                        (b0 * ns[i0] + hit.b1 * ns[i1] + hit.b2 * ns[i2]).try_normalize()
                    })
                    .map_or(geometric_normal, |n| if n.dot(geometric_normal) < 0.0 { -n } else { n });
                SurfaceHit {
                    t: hit.t,
                    p,
                    geometric_normal,
                    shading_normal,
                    material: m.material,
                    area_light: self.mesh_light[shape as usize],
                }
            }
            PrimGeometry::Sphere { center, radius } => {
                let n = (ray.at(hit.t) - center).normalize();
                SurfaceHit {
                    t: hit.t,
                    p: center + radius * n,
                    geometric_normal: n,
                    shading_normal: n,
                    material: self.scene.spheres[shape as usize].material,
                    area_light: self.sphere_light[shape as usize],
                }
            }
        })
    }
}
