//! What a render's image depends on, as the text a checkpoint carries
//! ([`crate::io::checkpoint`]), so that `--resume` never continues another
//! render: the scene's content, the settings and the camera, but not the
//! sample count.

use sha2::{Digest, Sha256};

use super::{CameraSettings, RenderSetup};
use crate::camera::ApertureShape;
use crate::render::RenderSettings;
use crate::scene::Scene;

/// A hash of a scene's content: every mesh array, material, light and the
/// view. Taken before the scene is compiled (which consumes it), and only
/// when checkpointing: a million triangles take a tenth of a second.
#[derive(Clone)]
pub struct SceneHash(Sha256);

impl SceneHash {
    /// The hash of `scene`.
    pub fn of(scene: &Scene) -> SceneHash {
        let mut hasher = Sha256::new();
        for mesh in &scene.meshes {
            let mut bytes = Vec::with_capacity(12 * mesh.positions.len() + 12 * mesh.indices.len());
            let floats = mesh
                .positions
                .iter()
                .chain(mesh.normals.iter().flatten())
                .flat_map(|v| v.to_array())
                .chain(mesh.uvs.iter().flatten().flat_map(|v| v.to_array()));
            for f in floats {
                bytes.extend_from_slice(&f.to_le_bytes());
            }
            for i in mesh.indices.iter().flatten() {
                bytes.extend_from_slice(&i.to_le_bytes());
            }
            hasher.update(&bytes);
            hasher.update(format!("{:?} {:?}", mesh.material, mesh.emission));
        }
        hasher.update(format!(
            "{:?} {:?} {:?} {:?}",
            scene.spheres, scene.materials, scene.lights, scene.view
        ));
        SceneHash(hasher)
    }
}

impl RenderSetup {
    /// This setup's render of the scene hashed as `scene` and called
    /// `scene_name`, as text: a readable head and a SHA-256 of the scene,
    /// the settings (but the sample count and the threads) and the camera.
    pub fn fingerprint(&self, scene: SceneHash, scene_name: &str) -> String {
        let SceneHash(mut hasher) = scene;
        let (settings, camera): (&RenderSettings, &CameraSettings) = (&self.settings, &self.camera);
        // A mask's Debug form gives only its size: its values go in as bytes.
        if let ApertureShape::Mask(mask) = camera.aperture() {
            let bytes: Vec<u8> = mask.values.iter().flat_map(|v| v.to_le_bytes()).collect();
            hasher.update(&bytes);
        }
        let described = RenderSettings {
            spp: 0,
            threads: None,
            ..*settings
        };
        hasher.update(format!("{described:?} {camera:?}"));
        let digest: String = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
        format!(
            "lenspath {} render of {scene_name}, {}x{}, seed {}; sha256 {digest}",
            env!("CARGO_PKG_VERSION"),
            settings.width,
            settings.height,
            settings.seed
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::builtin_scene;
    use crate::options::SceneOptions;
    use crate::setup::{resolve, RenderOverrides};

    /// The fingerprint tells renders apart by what their image depends on
    /// (the seed, the scene's content, the camera) and not by what it does
    /// not (the sample count, the threads).
    #[test]
    fn the_fingerprint_follows_what_the_image_depends_on() {
        let scene = builtin_scene("cornell-spheres", 0).unwrap();
        let view = scene.view.unwrap();
        let of = |scene: &Scene, overrides: RenderOverrides| {
            let setup = resolve(&SceneOptions::default(), &view, &overrides).unwrap();
            setup.fingerprint(SceneHash::of(scene), "cornell-spheres")
        };
        let base = of(&scene, RenderOverrides::default());
        let more_samples = RenderOverrides {
            spp: Some(7),
            threads: Some(1),
            ..RenderOverrides::default()
        };
        assert_eq!(of(&scene, more_samples), base);
        let other_seed = RenderOverrides {
            seed: Some(1),
            ..RenderOverrides::default()
        };
        assert_ne!(of(&scene, other_seed), base);
        let mut moved = scene.clone();
        moved.spheres[0].radius *= 1.001;
        assert_ne!(of(&moved, RenderOverrides::default()), base);
        assert!(
            base.starts_with("lenspath ") && base.contains("render of cornell-spheres, 640x480, seed 0"),
            "{base}"
        );
    }
}
