//! COLLADA 1.4 scenes (`.dae`), as Blender exports them and in the dialect of
//! the UC Berkeley CS184 path tracer (`<extra><technique profile="CGL">`,
//! also read under its older name `CMU462`).
//!
//! What is read (COLLADA 1.4.1 specification, Khronos 2008):
//! - geometry: `<triangles>`, `<polylist>` and `<polygons>` (fan-triangulated),
//!   positions and normals; CGL spheres (`<sphere><radius>`);
//! - the node tree with `<matrix>` (row-major), `<translate>`, `<rotate>`
//!   (axis, degrees), `<scale>` and `<lookat>`, applied in document order;
//!   `<instance_node>` (cycles are an error);
//! - cameras (`<perspective>` with `xfov`/`yfov`/`aspect_ratio`: the first one
//!   instanced is the view);
//! - lights: point, spot, directional and ambient (`technique_common`), and the
//!   CGL area light, a one-sided rectangle: unit square in the light's x–y plane,
//!   emitting along its −z (as the CS184 renderer's `AreaLight` does);
//! - materials: the CGL BSDFs (diffuse, mirror, glass, refraction, microfacet,
//!   emission) and otherwise the `profile_COMMON` diffuse and emission colours.
//!
//! Cameras in the CS184 dialect (any file using the CGL profile) are placed as
//! the CS184 renderer places them, which is not where their node puts them: it
//! looks at the centre of the scene's bounds from 1.5 bounds diagonals away,
//! along the unit vector to the point T·(0, 0, −1, 1) of the camera's node
//! transform T, with the file's up axis up (CS184 `Application::load` and
//! `Camera::place`). Without that, the course scenes would be framed
//! differently from the course renders.
//!
//! A `<matrix>` with fewer than 16 numbers is read as that renderer reads it,
//! the missing ones as 0, with a warning (CBgems.dae has one).
//!
//! The CS184 scenes describe their ceiling lamp twice: an area light (which that
//! renderer samples) and an emissive quad in the same place (which its camera
//! sees). Here both would emit, doubling the light, so an area light whose
//! centre lies on an emissive mesh facing the same way is dropped in favour of
//! the mesh (a warning says so).

use std::collections::HashMap;
use std::fmt;
use std::path::Path;

use glam::{Mat4, Vec3};
use roxmltree::{Document, Node};

use super::import::{
    focus_on_subject, intern_material, scene_bounds, transform_mesh, LoadedScene, MeshBuilder, SceneOptions, Warnings,
    DEFAULT_MATERIAL, DEFAULT_REFLECTANCE, EMITTER_MATERIAL, MAX_TRIANGLES,
};
use crate::camera::CameraPose;
use crate::error::{Error, Result};
use crate::glass::Dispersion;
use crate::lights::Light;
use crate::materials::Material;
use crate::math::Rgb;
use crate::scene::{Scene, SceneView};
use crate::shapes::{Sphere, TriangleMesh};
use crate::spectrum::Emission;

/// Deepest node nesting followed (instancing included).
const MAX_NODE_DEPTH: usize = 256;

/// Most node instances followed (shared subtrees can multiply exponentially).
const MAX_NODE_VISITS: usize = 1_000_000;

/// Reads a COLLADA file.
pub fn load_collada(path: &Path) -> Result<LoadedScene> {
    let text = crate::fs::read_text(path, crate::FileKind::Scene)?;
    parse_collada(&text, path)
}

/// Parses COLLADA text; `path` names the file in messages.
pub fn parse_collada(text: &str, path: &Path) -> Result<LoadedScene> {
    let doc = Document::parse(text).map_err(|e| Error::Parse {
        kind: crate::FileKind::Scene,
        path: path.to_path_buf(),
        message: format!("not well-formed XML: {e}"),
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        return Err(Error::Parse {
            kind: crate::FileKind::Scene,
            path: path.to_path_buf(),
            message: format!("root element is <{}>, not <COLLADA>", root.tag_name().name()),
        });
    }
    let mut reader = Reader {
        doc: &doc,
        path,
        ids: doc
            .descendants()
            .filter_map(|n| Some((n.attribute("id")?, n)))
            .collect(),
        scene: Scene::default(),
        warnings: Warnings::default(),
        geometries: HashMap::new(),
        materials: HashMap::new(),
        cameras: 0,
        triangles: 0,
        node_visits: 0,
        area_lights: Vec::new(),
        cs184: doc
            .descendants()
            .any(|n| n.has_tag_name("technique") && matches!(n.attribute("profile"), Some("CGL" | "CMU462"))),
        cs184_camera: None,
        up_axis: match path_child(root, "asset/up_axis").and_then(|n| n.text()).map(str::trim) {
            Some("Z_UP") => Vec3::Z,
            Some("X_UP") => Vec3::X,
            _ => Vec3::Y,
        },
    };
    let visual_scene = reader.visual_scene(root)?;
    for node in visual_scene.children().filter(|n| n.has_tag_name("node")) {
        reader.node(node, Mat4::IDENTITY, &mut Vec::new())?;
    }
    reader.place_area_lights();

    let mut options = SceneOptions::default();
    if let Some(unit) = child(root, "asset").and_then(|a| child(a, "unit")) {
        if let Some(meter) = unit.attribute("meter") {
            match meter.trim().parse::<f64>() {
                Ok(m) if m > 0.0 && m.is_finite() => options.scene_unit_m = Some(m),
                _ => reader
                    .warnings
                    .add(format!("<unit meter=\"{meter}\"> is not a positive number; ignored")),
            }
        }
    }
    Ok(LoadedScene::completed(
        reader.scene,
        options,
        reader.cameras,
        reader.warnings,
        "COLLADA",
    ))
}

/// Geometry parsed once per `<geometry>` and instanced any number of times.
#[derive(Clone)]
enum Geometry {
    /// Triangle meshes, one per primitive element, with its material symbol.
    Meshes(Vec<(Option<String>, TriangleMesh)>),
    /// A CGL sphere at the origin.
    Sphere { radius: f32 },
}

/// A material as the scene needs it: the surface and, for emitters, the radiance.
#[derive(Clone, Copy)]
struct SurfaceMaterial {
    material: Material,
    emission: Option<Rgb>,
}

/// A CGL area light waiting to become a quad (after the emissive meshes are known).
struct AreaLightQuad {
    name: String,
    corners: [Vec3; 4],
    normal: Vec3,
    radiance: Rgb,
}

struct Reader<'a, 'input> {
    doc: &'a Document<'input>,
    path: &'a Path,
    ids: HashMap<&'a str, Node<'a, 'input>>,
    scene: Scene,
    warnings: Warnings,
    geometries: HashMap<String, Geometry>,
    materials: HashMap<String, SurfaceMaterial>,
    cameras: usize,
    triangles: usize,
    node_visits: usize,
    area_lights: Vec<AreaLightQuad>,
    /// The file uses the CGL profile: place the camera as the CS184 renderer does.
    cs184: bool,
    /// CS184 camera: unit direction from the scene centre toward the camera, vertical fov.
    cs184_camera: Option<(Vec3, f32)>,
    /// The file's up axis.
    up_axis: Vec3,
}

/// First child element named `name`.
fn child<'a, 'input>(node: Node<'a, 'input>, name: &str) -> Option<Node<'a, 'input>> {
    node.children().find(|n| n.has_tag_name(name))
}

/// The element path `a/b/c` below `node`.
fn path_child<'a, 'input>(node: Node<'a, 'input>, path: &str) -> Option<Node<'a, 'input>> {
    path.split('/').try_fold(node, |n, name| child(n, name))
}

/// First child element, whatever its name.
fn first_element<'a, 'input>(node: Node<'a, 'input>) -> Option<Node<'a, 'input>> {
    node.children().find(Node::is_element)
}

/// The `<extra><technique profile="CGL">` (or `CMU462`) of `node`.
fn cgl_technique<'a, 'input>(node: Node<'a, 'input>) -> Option<Node<'a, 'input>> {
    node.children()
        .filter(|n| n.has_tag_name("extra"))
        .flat_map(|e| e.children())
        .find(|t| t.has_tag_name("technique") && matches!(t.attribute("profile"), Some("CGL" | "CMU462")))
}

impl<'a, 'input> Reader<'a, 'input> {
    /// A parse error at `node`: line, element (with its id) and what is wrong.
    fn error(&self, node: Node, message: impl fmt::Display) -> Error {
        let pos = self.doc.text_pos_at(node.range().start);
        let id = node.attribute("id").map_or(String::new(), |id| format!(" id=\"{id}\""));
        Error::Parse {
            kind: crate::FileKind::Scene,
            path: self.path.to_path_buf(),
            message: format!("line {}: <{}{id}>: {message}", pos.row, node.tag_name().name()),
        }
    }

    /// The numbers in `node`'s text.
    fn numbers(&self, node: Node) -> Result<Vec<f32>> {
        let text = node.text().unwrap_or("");
        text.split_ascii_whitespace()
            .map(|t| {
                let v: f32 = t
                    .parse()
                    .map_err(|_| self.error(node, format!("'{t}' is not a number")))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(self.error(node, format!("'{t}' is not finite")))
                }
            })
            .collect()
    }

    /// Exactly `n` numbers in `node`'s text.
    fn fixed<const N: usize>(&self, node: Node) -> Result<[f32; N]> {
        let v = self.numbers(node)?;
        v.as_slice()
            .try_into()
            .map_err(|_| self.error(node, format!("expected {N} numbers, found {}", v.len())))
    }

    /// An RGB colour from 3 or 4 (RGBA) numbers.
    fn color(&self, node: Node) -> Result<Rgb> {
        let v = self.numbers(node)?;
        match v[..] {
            [r, g, b] | [r, g, b, _] => Ok(Rgb::new(r, g, b)),
            _ => Err(self.error(node, format!("expected an RGB colour, found {} numbers", v.len()))),
        }
    }

    /// One number in a required child element.
    fn scalar(&self, parent: Node, name: &str) -> Result<f32> {
        let node = child(parent, name).ok_or_else(|| self.error(parent, format!("missing <{name}>")))?;
        Ok(self.fixed::<1>(node)?[0])
    }

    /// An RGB colour in a required child element.
    fn color_child(&self, parent: Node, name: &str) -> Result<Rgb> {
        let node = child(parent, name).ok_or_else(|| self.error(parent, format!("missing <{name}>")))?;
        self.color(node)
    }

    /// The element `url` (`#id`) refers to, which must be a `<tag>`.
    fn resolve(&self, from: Node, url: Option<&str>, tag: &str) -> Result<Node<'a, 'input>> {
        let url = url.ok_or_else(|| self.error(from, "missing url"))?;
        let id = url.strip_prefix('#').ok_or_else(|| {
            self.error(
                from,
                format!("url '{url}' refers to another file; only '#id' references are supported"),
            )
        })?;
        let target = *self
            .ids
            .get(id)
            .ok_or_else(|| self.error(from, format!("'{url}' refers to nothing in this file")))?;
        if !target.has_tag_name(tag) {
            return Err(self.error(
                from,
                format!("'{url}' is a <{}>, not a <{tag}>", target.tag_name().name()),
            ));
        }
        Ok(target)
    }

    /// The `<visual_scene>` the `<scene>` element instances (or the first one).
    fn visual_scene(&mut self, root: Node<'a, 'input>) -> Result<Node<'a, 'input>> {
        if let Some(inst) = path_child(root, "scene/instance_visual_scene") {
            return self.resolve(inst, inst.attribute("url"), "visual_scene");
        }
        let first = root.descendants().find(|n| n.has_tag_name("visual_scene"));
        match first {
            Some(vs) => {
                self.warnings
                    .add("no <scene><instance_visual_scene>: used the first <visual_scene>");
                Ok(vs)
            }
            None => Err(self.error(root, "no <visual_scene>: the file has nothing to render")),
        }
    }

    /// The node's local transform: its transform elements, composed in document order.
    fn local_transform(&mut self, node: Node) -> Result<Mat4> {
        let mut m = Mat4::IDENTITY;
        for t in node.children().filter(Node::is_element) {
            let step = match t.tag_name().name() {
                "matrix" => {
                    let mut v = self.numbers(t)?;
                    if v.len() > 16 {
                        return Err(self.error(t, format!("expected 16 numbers, found {}", v.len())));
                    }
                    if v.len() < 16 {
                        let pos = self.doc.text_pos_at(t.range().start);
                        self.warnings.add(format!(
                            "line {}: <matrix> has {} numbers, not 16; the missing ones are read as 0, as the CS184 renderer does",
                            pos.row,
                            v.len()
                        ));
                        v.resize(16, 0.0);
                    }
                    Mat4::from_cols_slice(&v).transpose()
                }
                "translate" => Mat4::from_translation(Vec3::from_array(self.fixed::<3>(t)?)),
                "scale" => Mat4::from_scale(Vec3::from_array(self.fixed::<3>(t)?)),
                "rotate" => {
                    let [x, y, z, degrees] = self.fixed::<4>(t)?;
                    let axis = Vec3::new(x, y, z)
                        .try_normalize()
                        .ok_or_else(|| self.error(t, "rotation axis is zero"))?;
                    Mat4::from_axis_angle(axis, degrees.to_radians())
                }
                "lookat" => {
                    let v = self.fixed::<9>(t)?;
                    let (eye, target, up) = (
                        Vec3::new(v[0], v[1], v[2]),
                        Vec3::new(v[3], v[4], v[5]),
                        Vec3::new(v[6], v[7], v[8]),
                    );
                    if (target - eye).cross(up).length_squared() == 0.0 {
                        return Err(self.error(t, "eye, interest point and up are degenerate"));
                    }
                    // The frame whose −z looks from eye to target, +y up (COLLADA §5 <lookat>).
                    let forward = (target - eye).normalize();
                    let right = forward.cross(up).normalize();
                    let true_up = right.cross(forward);
                    Mat4::from_cols(
                        right.extend(0.0),
                        true_up.extend(0.0),
                        (-forward).extend(0.0),
                        eye.extend(1.0),
                    )
                }
                "skew" => {
                    self.warnings.add("<skew> transforms are not supported; ignored");
                    continue;
                }
                _ => continue,
            };
            m *= step;
        }
        Ok(m)
    }

    /// Walks a `<node>` and its children, instancing what they hold.
    fn node(&mut self, node: Node<'a, 'input>, parent: Mat4, stack: &mut Vec<Node<'a, 'input>>) -> Result<()> {
        if stack.contains(&node) {
            return Err(self.error(node, "node instancing forms a cycle"));
        }
        if stack.len() >= MAX_NODE_DEPTH {
            return Err(self.error(node, format!("nodes nest deeper than {MAX_NODE_DEPTH} levels")));
        }
        self.node_visits += 1;
        if self.node_visits > MAX_NODE_VISITS {
            return Err(self.error(node, format!("instancing expands to more than {MAX_NODE_VISITS} nodes")));
        }
        let world = parent * self.local_transform(node)?;
        if !world.is_finite() {
            return Err(self.error(node, "transform is not finite"));
        }
        stack.push(node);
        for item in node.children().filter(Node::is_element) {
            match item.tag_name().name() {
                "node" => self.node(item, world, stack)?,
                "instance_node" => {
                    let target = self.resolve(item, item.attribute("url"), "node")?;
                    self.node(target, world, stack)?;
                }
                "instance_geometry" => self.instance_geometry(item, &world)?,
                "instance_light" => self.instance_light(item, &world)?,
                "instance_camera" => self.instance_camera(item, &world)?,
                "instance_controller" => self
                    .warnings
                    .add("<instance_controller> (skinned or morphed geometry) is not supported; skipped"),
                _ => {}
            }
        }
        stack.pop();
        Ok(())
    }

    fn instance_camera(&mut self, item: Node, world: &Mat4) -> Result<()> {
        let camera = self.resolve(item, item.attribute("url"), "camera")?;
        self.cameras += 1;
        if self.scene.view.is_some() {
            return Ok(());
        }
        let Some(perspective) = path_child(camera, "optics/technique_common/perspective") else {
            self.warnings
                .add("a camera is not perspective (orthographic is not supported); skipped");
            return Ok(());
        };
        let optional = |name: &str| -> Result<Option<f32>> {
            child(perspective, name)
                .map(|n| self.fixed::<1>(n).map(|[v]| v))
                .transpose()
        };
        let (xfov, yfov, aspect) = (optional("xfov")?, optional("yfov")?, optional("aspect_ratio")?);
        let fov_y_deg = match (xfov, yfov, aspect) {
            (_, Some(y), _) => y,
            (Some(x), None, Some(a)) if a > 0.0 => 2.0 * ((0.5 * x.to_radians()).tan() / a).atan().to_degrees(),
            (Some(x), None, None) => x,
            _ => return Err(self.error(perspective, "needs <yfov>, or <xfov> with <aspect_ratio>")),
        };
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(self.error(
                perspective,
                format!("field of view {fov_y_deg}° is not between 0 and 180"),
            ));
        }
        if self.cs184 {
            let toward = world.transform_point3(Vec3::NEG_Z).try_normalize();
            self.cs184_camera = Some((
                toward.ok_or_else(|| self.error(item, "camera view direction is zero"))?,
                fov_y_deg,
            ));
            return Ok(());
        }
        // COLLADA cameras look down their −z with +y up.
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z);
        let up = world.transform_vector3(Vec3::Y);
        let pose = CameraPose::try_look_at(eye, eye + forward, up)
            .map_err(|m| self.error(item, format!("camera transform: {m}")))?;
        self.scene.view = Some(SceneView {
            pose,
            fov_y_deg,
            focus_distance: 0.0, // set from the scene bounds once everything is loaded
        });
        Ok(())
    }

    fn instance_light(&mut self, item: Node, world: &Mat4) -> Result<()> {
        let light = self.resolve(item, item.attribute("url"), "light")?;
        let name = light
            .attribute("name")
            .or(light.attribute("id"))
            .unwrap_or("light")
            .to_string();
        let position = world.transform_point3(Vec3::ZERO);
        let axis = world.transform_vector3(Vec3::NEG_Z).try_normalize();
        // The CGL profile wins over technique_common, as in the CS184 renderer.
        let spec = cgl_technique(light)
            .and_then(first_element)
            .or_else(|| child(light, "technique_common").and_then(first_element))
            .ok_or_else(|| self.error(light, "no light definition"))?;
        let axis_or_err = |r: &Self| axis.ok_or_else(|| r.error(item, "light transform is degenerate"));
        let new = match spec.tag_name().name() {
            "area" => {
                let radiance = self.color_child(spec, "color")?;
                let dx = world.transform_vector3(Vec3::X) * 0.5;
                let dy = world.transform_vector3(Vec3::Y) * 0.5;
                let normal = axis_or_err(self)?;
                let corners = [
                    position - dx - dy,
                    position + dx - dy,
                    position + dx + dy,
                    position - dx + dy,
                ];
                self.area_lights.push(AreaLightQuad {
                    name,
                    corners,
                    normal,
                    radiance,
                });
                return Ok(());
            }
            "point" => Light::Point {
                position,
                intensity: self.color_child(spec, "color")?.into(),
            },
            "spot" => {
                let falloff_deg = match child(spec, "falloff_angle") {
                    Some(n) => self.fixed::<1>(n)?[0],
                    None => 180.0,
                };
                let exponent = match child(spec, "falloff_exponent") {
                    Some(n) => self.fixed::<1>(n)?[0],
                    None => 0.0,
                };
                if !(falloff_deg > 0.0 && falloff_deg <= 360.0 && exponent >= 0.0) {
                    return Err(self.error(spec, "falloff_angle must be in (0, 360] and falloff_exponent ≥ 0"));
                }
                Light::Spot {
                    position,
                    direction: axis_or_err(self)?,
                    intensity: self.color_child(spec, "color")?.into(),
                    cos_cutoff: (0.5 * falloff_deg).min(180.0).to_radians().cos(),
                    exponent,
                }
            }
            "directional" => Light::Directional {
                direction: axis_or_err(self)?,
                irradiance: self.color_child(spec, "color")?.into(),
            },
            "ambient" => Light::Environment {
                radiance: self.color_child(spec, "color")?.into(),
            },
            other => {
                return Err(self.error(
                    spec,
                    format!("unknown light type <{other}>; expected point, spot, directional, ambient or CGL area"),
                ))
            }
        };
        self.scene.lights.push(new);
        Ok(())
    }

    fn instance_geometry(&mut self, item: Node<'a, 'input>, world: &Mat4) -> Result<()> {
        let geometry_node = self.resolve(item, item.attribute("url"), "geometry")?;
        let id = geometry_node.attribute("id").unwrap_or_default().to_string();
        let geometry = match self.geometries.get(&id) {
            Some(g) => g.clone(),
            None => {
                let g = self.geometry(geometry_node)?;
                self.geometries.insert(id, g.clone());
                g
            }
        };
        // symbol → material element
        let mut bindings = HashMap::new();
        for im in item.descendants().filter(|n| n.has_tag_name("instance_material")) {
            if let Some(symbol) = im.attribute("symbol") {
                bindings.insert(
                    symbol.to_string(),
                    self.resolve(im, im.attribute("target"), "material")?,
                );
            }
        }
        let surface_for = |r: &mut Self, symbol: Option<&str>| -> Result<SurfaceMaterial> {
            let target = match symbol {
                Some(s) => bindings.get(s).copied(),
                None => bindings.values().next().copied(),
            };
            match target {
                Some(material) => r.material(material),
                None => {
                    r.warnings.add("geometry without a bound material: used grey diffuse");
                    Ok(SurfaceMaterial {
                        material: DEFAULT_MATERIAL,
                        emission: None,
                    })
                }
            }
        };
        match geometry {
            Geometry::Sphere { radius } => {
                let surface = surface_for(self, None)?;
                let center = world.transform_point3(Vec3::ZERO);
                let axes = [Vec3::X, Vec3::Y, Vec3::Z].map(|a| world.transform_vector3(a).length());
                let scale = (axes[0] * axes[1] * axes[2]).cbrt();
                if axes.iter().any(|a| (a - scale).abs() > 1e-3 * scale) {
                    self.warnings
                        .add("a sphere is scaled unevenly; rendered as a sphere of the mean scale");
                }
                let material = intern_material(&mut self.scene, surface.material);
                self.scene.spheres.push(Sphere {
                    center,
                    radius: radius * scale,
                    material,
                    emission: surface.emission.map(Emission::from),
                });
            }
            Geometry::Meshes(meshes) => {
                for (symbol, mut mesh) in meshes {
                    self.triangles += mesh.indices.len();
                    if self.triangles > MAX_TRIANGLES {
                        return Err(self.error(
                            item,
                            format!("instancing expands the scene beyond {MAX_TRIANGLES} triangles"),
                        ));
                    }
                    let surface = surface_for(self, symbol.as_deref())?;
                    transform_mesh(&mut mesh, world);
                    mesh.material = intern_material(&mut self.scene, surface.material);
                    mesh.emission = surface.emission.map(Emission::from);
                    self.scene.meshes.push(mesh);
                }
            }
        }
        Ok(())
    }

    /// Reads a `<geometry>`: a CGL sphere or a `<mesh>`.
    fn geometry(&mut self, geometry: Node<'a, 'input>) -> Result<Geometry> {
        if let Some(sphere) = cgl_technique(geometry).and_then(|t| child(t, "sphere")) {
            let radius = self.scalar(sphere, "radius")?;
            if radius <= 0.0 {
                return Err(self.error(sphere, format!("radius must be positive, got {radius}")));
            }
            return Ok(Geometry::Sphere { radius });
        }
        let Some(mesh) = child(geometry, "mesh") else {
            self.warnings
                .add("geometry that is neither a <mesh> nor a CGL sphere (splines, convex meshes); skipped");
            return Ok(Geometry::Meshes(Vec::new()));
        };
        let name = geometry.attribute("id").unwrap_or("geometry");
        let mut out = Vec::new();
        for prim in mesh.children().filter(Node::is_element) {
            let kind = prim.tag_name().name();
            if !matches!(kind, "triangles" | "polylist" | "polygons") {
                if matches!(kind, "lines" | "linestrips" | "trifans" | "tristrips") {
                    self.warnings
                        .add(format!("<{kind}> primitives are not supported; skipped"));
                }
                continue;
            }
            let built = self.primitive(prim)?;
            let tri_mesh = built.finish(name, &mut self.warnings);
            if !tri_mesh.indices.is_empty() {
                out.push((prim.attribute("material").map(str::to_string), tri_mesh));
            }
        }
        Ok(Geometry::Meshes(out))
    }

    /// The float array of a `<source>`, with the accessor's stride.
    fn source(&self, from: Node, url: Option<&str>, width: usize) -> Result<Vec<f32>> {
        let source = self.resolve(from, url, "source")?;
        let array = child(source, "float_array").ok_or_else(|| self.error(source, "has no <float_array>"))?;
        let values = self.numbers(array)?;
        if let Some(count) = array.attribute("count") {
            if count.parse::<usize>().ok() != Some(values.len()) {
                return Err(self.error(
                    array,
                    format!("count=\"{count}\" but it holds {} numbers", values.len()),
                ));
            }
        }
        let stride = match path_child(source, "technique_common/accessor").and_then(|a| a.attribute("stride")) {
            Some(s) => s
                .parse::<usize>()
                .ok()
                .filter(|&s| s >= width)
                .ok_or_else(|| self.error(source, format!("accessor stride '{s}' must be at least {width}")))?,
            None => width,
        };
        if values.len() % stride != 0 {
            return Err(self.error(
                array,
                format!("{} numbers do not divide into elements of {stride}", values.len()),
            ));
        }
        Ok(values
            .chunks_exact(stride)
            .flat_map(|c| c[..width].iter().copied())
            .collect())
    }

    /// One `<triangles>`, `<polylist>` or `<polygons>` element as a mesh with one
    /// index per corner (position and normal pairs become vertices).
    fn primitive(&mut self, prim: Node<'a, 'input>) -> Result<MeshBuilder> {
        // Inputs: VERTEX (→ <vertices> → POSITION, maybe NORMAL) and NORMAL, each at an offset.
        let mut stride = 0;
        let mut position_input = None;
        let mut normal_input = None;
        for input in prim.children().filter(|n| n.has_tag_name("input")) {
            let offset: usize = input
                .attribute("offset")
                .unwrap_or("0")
                .parse()
                .map_err(|_| self.error(input, "offset is not a whole number"))?;
            if offset > 64 {
                return Err(self.error(input, format!("offset {offset} is absurd")));
            }
            stride = stride.max(offset + 1);
            match input.attribute("semantic") {
                Some("VERTEX") => {
                    let vertices = self.resolve(input, input.attribute("source"), "vertices")?;
                    for vi in vertices.children().filter(|n| n.has_tag_name("input")) {
                        match vi.attribute("semantic") {
                            Some("POSITION") => {
                                position_input = Some((offset, self.source(vi, vi.attribute("source"), 3)?))
                            }
                            Some("NORMAL") => {
                                normal_input = Some((offset, self.source(vi, vi.attribute("source"), 3)?))
                            }
                            _ => {}
                        }
                    }
                }
                Some("NORMAL") => normal_input = Some((offset, self.source(input, input.attribute("source"), 3)?)),
                _ => {}
            }
        }
        let (position_offset, positions) =
            position_input.ok_or_else(|| self.error(prim, "no VERTEX input with POSITION"))?;
        let position_count = positions.len() / 3;
        let normal_count = normal_input.as_ref().map_or(0, |(_, n)| n.len() / 3);

        // Polygon sizes, and the index lists they come in.
        let kind = prim.tag_name().name();
        let declared: Option<usize> = prim.attribute("count").and_then(|c| c.parse().ok());
        let mut polygons: Vec<(Node, Vec<usize>)> = Vec::new(); // (<p>, corner counts)
        match kind {
            "polygons" => {
                for p in prim.children().filter(|n| n.has_tag_name("p")) {
                    polygons.push((p, vec![usize::MAX])); // one polygon: every index in <p>
                }
                if prim.children().any(|n| n.has_tag_name("ph")) {
                    self.warnings
                        .add("<ph> polygons with holes: holes ignored, outer loop kept");
                }
            }
            _ => {
                let p = child(prim, "p").ok_or_else(|| self.error(prim, "no <p> index list"))?;
                let sizes = if kind == "polylist" {
                    let vcount = child(prim, "vcount").ok_or_else(|| self.error(prim, "no <vcount>"))?;
                    let sizes = vcount
                        .text()
                        .unwrap_or("")
                        .split_ascii_whitespace()
                        .map(|t| {
                            t.parse::<usize>()
                                .map_err(|_| self.error(vcount, format!("'{t}' is not a whole number")))
                        })
                        .collect::<Result<Vec<_>>>()?;
                    if let Some(d) = declared {
                        if d != sizes.len() {
                            return Err(self.error(
                                prim,
                                format!("count=\"{d}\" but <vcount> lists {} polygons", sizes.len()),
                            ));
                        }
                    }
                    sizes
                } else {
                    let d = declared.ok_or_else(|| self.error(prim, "missing or bad count attribute"))?;
                    // Each index takes at least two characters: refuse a count the <p> cannot hold
                    // before allocating for it.
                    let room = p.text().map_or(0, str::len) / 2 + 1;
                    if d.saturating_mul(3 * stride) > room {
                        return Err(self.error(
                            p,
                            format!("count=\"{d}\" triangles need more indices than this <p> holds"),
                        ));
                    }
                    vec![3; d]
                };
                polygons.push((p, sizes));
            }
        }

        let mut builder = MeshBuilder::default();
        let mut vertex_of: HashMap<(u32, u32), u32> = HashMap::new();
        let mut normals = Vec::new();
        for (p, sizes) in polygons {
            let indices = p
                .text()
                .unwrap_or("")
                .split_ascii_whitespace()
                .map(|t| {
                    t.parse::<u32>()
                        .map_err(|_| self.error(p, format!("'{t}' is not a vertex index")))
                })
                .collect::<Result<Vec<_>>>()?;
            let sizes = if sizes == [usize::MAX] {
                vec![indices.len() / stride]
            } else {
                sizes
            };
            let needed: usize = sizes
                .iter()
                .try_fold(0usize, |acc, &s| acc.checked_add(s.checked_mul(stride)?))
                .ok_or_else(|| self.error(p, "polygon sizes overflow"))?;
            if indices.len() != needed {
                return Err(self.error(
                    p,
                    format!(
                        "holds {} indices, but {} polygons of these sizes with {stride} inputs need {needed}",
                        indices.len(),
                        sizes.len()
                    ),
                ));
            }
            let mut corner = 0;
            let mut polygon = Vec::new();
            for size in sizes {
                polygon.clear();
                for _ in 0..size {
                    let at = corner * stride;
                    corner += 1;
                    let pi = indices[at + position_offset];
                    if pi as usize >= position_count {
                        return Err(self.error(
                            p,
                            format!("position index {pi} is out of range (the source has {position_count})"),
                        ));
                    }
                    let ni = match &normal_input {
                        Some((off, _)) => {
                            let ni = indices[at + off];
                            if ni as usize >= normal_count {
                                return Err(self.error(
                                    p,
                                    format!("normal index {ni} is out of range (the source has {normal_count})"),
                                ));
                            }
                            ni
                        }
                        None => 0,
                    };
                    let v = *vertex_of.entry((pi, ni)).or_insert_with(|| {
                        let i = pi as usize * 3;
                        builder
                            .mesh
                            .positions
                            .push(Vec3::new(positions[i], positions[i + 1], positions[i + 2]));
                        if let Some((_, ns)) = &normal_input {
                            let j = ni as usize * 3;
                            normals.push(Vec3::new(ns[j], ns[j + 1], ns[j + 2]));
                        }
                        (builder.mesh.positions.len() - 1) as u32
                    });
                    polygon.push(v);
                }
                builder.polygon(&polygon);
            }
        }
        if normal_input.is_some() {
            builder.mesh.normals = Some(normals);
        }
        Ok(builder)
    }

    /// The lenspath material for a `<material>`, converted once.
    fn material(&mut self, material: Node<'a, 'input>) -> Result<SurfaceMaterial> {
        let id = material.attribute("id").unwrap_or_default().to_string();
        if let Some(m) = self.materials.get(&id) {
            return Ok(*m);
        }
        let inst = child(material, "instance_effect").ok_or_else(|| self.error(material, "no <instance_effect>"))?;
        let effect = self.resolve(inst, inst.attribute("url"), "effect")?;
        let surface = self.effect(effect)?;
        self.materials.insert(id, surface);
        Ok(surface)
    }

    /// An effect's BSDF: the CGL one when present, else the common profile's colours.
    fn effect(&mut self, effect: Node) -> Result<SurfaceMaterial> {
        let plain = |material| SurfaceMaterial {
            material,
            emission: None,
        };
        if let Some(bsdf) = cgl_technique(effect).and_then(first_element) {
            return Ok(match bsdf.tag_name().name() {
                "diffuse" => plain(Material::Diffuse {
                    reflectance: self.color_child(bsdf, "reflectance")?,
                }),
                "mirror" => plain(Material::Mirror {
                    reflectance: self.color_child(bsdf, "reflectance")?,
                }),
                "glass" | "refraction" => {
                    let glass = bsdf.has_tag_name("glass");
                    let eta = self.scalar(bsdf, "ior")?;
                    if eta <= 0.0 {
                        return Err(self.error(bsdf, format!("ior must be positive, got {eta}")));
                    }
                    if child(bsdf, "roughness").is_some() && self.scalar(bsdf, "roughness")? > 0.0 {
                        self.warnings.add("rough glass is rendered smooth (lenspath's dielectric is smooth)");
                    }
                    // lenspath's extension: an <abbe> (V_d) child makes the glass disperse.
                    let eta = match child(bsdf, "abbe") {
                        None => Dispersion::Constant(f64::from(eta)),
                        Some(_) => {
                            let v_d = self.scalar(bsdf, "abbe")?;
                            Dispersion::from_abbe(f64::from(eta), f64::from(v_d))
                                .map_err(|e| self.error(bsdf, e.to_string()))?
                        }
                    };
                    plain(Material::Dielectric {
                        eta,
                        // The CS184 refraction BSDF transmits only: no reflected lobe.
                        reflectance: if glass { self.color_child(bsdf, "reflectance")? } else { Rgb::ZERO },
                        transmittance: self.color_child(bsdf, "transmittance")?,
                    })
                }
                "microfacet" => {
                    let alpha = self.scalar(bsdf, "alpha")?;
                    if alpha < 0.0 {
                        return Err(self.error(bsdf, format!("alpha must be ≥ 0, got {alpha}")));
                    }
                    plain(Material::Conductor {
                        eta: self.color_child(bsdf, "eta")?,
                        k: self.color_child(bsdf, "k")?,
                        alpha,
                    })
                }
                "emission" => SurfaceMaterial {
                    material: EMITTER_MATERIAL,
                    emission: Some(self.color_child(bsdf, "radiance")?),
                },
                other => {
                    return Err(self.error(bsdf, format!(
                        "unknown CGL BSDF <{other}>; expected diffuse, mirror, glass, refraction, microfacet or emission"
                    )))
                }
            });
        }
        let shading = path_child(effect, "profile_COMMON/technique").and_then(|t| {
            t.children()
                .find(|n| matches!(n.tag_name().name(), "phong" | "lambert" | "blinn" | "constant"))
        });
        let Some(shading) = shading else {
            self.warnings
                .add("an effect without a common-profile shading model: used grey diffuse");
            return Ok(plain(DEFAULT_MATERIAL));
        };
        let mut reflectance = DEFAULT_REFLECTANCE;
        if let Some(diffuse) = child(shading, "diffuse") {
            if let Some(color) = child(diffuse, "color") {
                reflectance = self.color(color)?;
            } else if child(diffuse, "texture").is_some() {
                self.warnings
                    .add("diffuse textures are not supported: used grey diffuse");
            }
        }
        let emission = match path_child(shading, "emission/color") {
            Some(c) => Some(self.color(c)?).filter(|e| e.max_element() > 0.0),
            None => None,
        };
        Ok(SurfaceMaterial {
            material: Material::Diffuse {
                reflectance: reflectance.clamp(Rgb::ZERO, Rgb::ONE),
            },
            emission,
        })
    }

    /// Turns the CGL area lights into emissive quads, except those that an
    /// emissive mesh already draws (see the module notes).
    fn place_area_lights(&mut self) {
        for light in std::mem::take(&mut self.area_lights) {
            let center = 0.25 * light.corners.iter().copied().sum::<Vec3>();
            let size = (light.corners[2] - light.corners[0]).length();
            let drawn = self.scene.meshes.iter().any(|m| {
                m.emission.as_ref().is_some_and(|e| !e.is_black())
                    && m.triangles().any(|[a, b, c]| {
                        let n = (b - a).cross(c - a).normalize_or_zero();
                        n.dot(light.normal) > 0.99
                            && (center - a).dot(n).abs() < 0.02 * size
                            && inside_triangle_projected(center, [a, b, c], n)
                    })
            });
            if drawn {
                self.warnings.add(format!(
                    "area light '{}' lies on an emissive mesh facing the same way: kept the mesh only, so the lamp is not counted twice",
                    light.name
                ));
                continue;
            }
            let [a, b, c, d] = light.corners;
            let mut mesh = TriangleMesh {
                positions: vec![a, b, c, d],
                indices: vec![[0, 1, 2], [0, 2, 3]],
                ..Default::default()
            };
            // Wind the quad so its front face (counter-clockwise) faces the light's direction.
            if (b - a).cross(c - a).dot(light.normal) < 0.0 {
                for t in &mut mesh.indices {
                    t.swap(1, 2);
                }
            }
            mesh.material = intern_material(&mut self.scene, EMITTER_MATERIAL);
            mesh.emission = Some(light.radiance.into());
            self.scene.meshes.push(mesh);
        }
        if let Some((toward, fov_y_deg)) = self.cs184_camera {
            let bounds = scene_bounds(&self.scene);
            if !bounds.is_empty() {
                let target = Vec3::from(bounds.centroid());
                let eye = target + 1.5 * bounds.diagonal().length() * toward;
                let up = if toward.cross(self.up_axis).length_squared() > 1e-6 {
                    self.up_axis
                } else {
                    toward.any_orthonormal_vector()
                };
                self.scene.view = Some(SceneView {
                    pose: CameraPose::look_at(eye, target, up),
                    fov_y_deg,
                    focus_distance: 0.0,
                });
            }
        }
        focus_on_subject(&mut self.scene);
    }
}

/// True when `p`, projected along `n` onto the triangle's plane, lies inside it.
fn inside_triangle_projected(p: Vec3, [a, b, c]: [Vec3; 3], n: Vec3) -> bool {
    let edge = |u: Vec3, v: Vec3| (v - u).cross(p - u).dot(n) >= -1e-6;
    edge(a, b) && edge(b, c) && edge(c, a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Blender-style file: transforms composed in document order, a shared
    /// node instanced twice, a `<polygons>` quad, spot and ambient lights, a
    /// `<lookat>` camera with `yfov`.
    #[test]
    fn transforms_instancing_polygons_lights_and_camera() {
        let text = r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="0.01"/><up_axis>Y_UP</up_axis></asset>
  <library_cameras><camera id="cam"><optics><technique_common><perspective><yfov>30</yfov></perspective></technique_common></optics></camera></library_cameras>
  <library_lights>
    <light id="spot"><technique_common><spot><color>2 2 2</color><falloff_angle>60</falloff_angle><falloff_exponent>1</falloff_exponent></spot></technique_common></light>
    <light id="sky"><technique_common><ambient><color>0.1 0.2 0.3</color></ambient></technique_common></light>
  </library_lights>
  <library_geometries>
    <geometry id="quad"><mesh>
      <source id="p"><float_array id="pa" count="12">0 0 0 1 0 0 1 1 0 0 1 0</float_array>
        <technique_common><accessor source="#pa" count="4" stride="3"/></technique_common></source>
      <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
      <polygons count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2 3</p></polygons>
    </mesh></geometry>
  </library_geometries>
  <library_nodes>
    <node id="shared"><scale>2 2 2</scale><instance_geometry url="#quad"/></node>
  </library_nodes>
  <library_visual_scenes><visual_scene id="s">
    <node id="a"><translate>10 0 0</translate><rotate>0 0 1 90</rotate><instance_node url="#shared"/></node>
    <node id="b"><translate>0 0 -5</translate><instance_node url="#shared"/>
      <node id="lamp"><translate>0 3 0</translate><rotate>1 0 0 -90</rotate><instance_light url="#spot"/></node>
    </node>
    <node id="amb"><instance_light url="#sky"/></node>
    <node id="c"><lookat>0 0 10  0 0 0  0 1 0</lookat><instance_camera url="#cam"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##;
        let loaded = parse_collada(text, Path::new("t.dae")).unwrap();
        let s = &loaded.scene;
        assert_eq!(loaded.options.scene_unit_m, Some(0.01));
        assert_eq!(s.meshes.len(), 2);
        assert_eq!(s.triangle_count(), 4);
        // Node a: scale 2, then rotate 90° about z, then translate: (1,0,0) → (2,0,0) → (0,2,0) → (10,2,0).
        let p = s.meshes[0].positions[1];
        assert!((p - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5, "{p}");
        assert!((s.meshes[1].positions[2] - Vec3::new(2.0, 2.0, -5.0)).length() < 1e-5);
        let Light::Spot {
            position,
            direction,
            cos_cutoff,
            exponent,
            ..
        } = s.lights[0]
        else {
            panic!("{:?}", s.lights[0]);
        };
        // The lamp's −z turned −90° about x points down −y.
        assert!((position - Vec3::new(0.0, 3.0, -5.0)).length() < 1e-5);
        assert!((direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
        assert!((cos_cutoff - 30f32.to_radians().cos()).abs() < 1e-6 && exponent == 1.0);
        assert!(
            matches!(s.lights[1], Light::Environment { ref radiance } if *radiance == Rgb::new(0.1, 0.2, 0.3).into())
        );
        let view = s.view.unwrap();
        assert_eq!(view.fov_y_deg, 30.0);
        let m = view.pose.render_from_camera;
        assert!((Vec3::from(m.translation) - Vec3::new(0.0, 0.0, 10.0)).length() < 1e-5);
        assert!(
            (Vec3::from(m.matrix3.z_axis) - Vec3::NEG_Z).length() < 1e-5,
            "looks at the origin"
        );
        assert_eq!(
            loaded.warnings.to_string(),
            "geometry without a bound material: used grey diffuse (×2)"
        );
    }
}
