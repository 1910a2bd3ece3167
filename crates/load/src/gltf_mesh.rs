//! glTF 2.0 (.gltf with external or data-URI buffers, and .glb) → triangles, materials and
//! point lights.
//!
//! The `gltf` crate parses and validates the JSON; buffers are resolved here (its `import`
//! feature would pull in image decoding). Every accessor is checked against its buffer before
//! the crate's reader touches it, because that reader trusts the file: a zero count, a stride
//! shorter than the element or a type mismatch would otherwise panic or misread.

use std::collections::HashMap;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use base64::Engine;
use bdpm_geometry::TriangleMesh;
use bdpm_scene::{PointLight, TexelImage, Texture, Wrap};
use glam::{Affine2, Mat2, Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::extensions::scene::khr_lights_punctual::Type as LightType;
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use gltf::{Accessor, Node, Semantic};

use crate::LoadError;
use crate::gltf_material::{Made, Tally, make};
use crate::materials::Materials;
use crate::memory::Budget;

/// Deepest node nesting accepted. glTF forbids cycles but the parser does not check for them,
/// so the walk stops here instead of running forever.
const MAX_DEPTH: usize = 256;
/// Most node visits accepted (a node reachable along many paths is visited once per path).
const MAX_VISITS: usize = 1_000_000;

/// What one glTF file contributes to the scene.
#[derive(Debug, Default)]
pub(crate) struct GltfPart {
    /// Triangles; `normals` is either one per vertex (zero = flat) or empty.
    pub(crate) mesh: TriangleMesh,
    pub(crate) lights: Vec<PointLight>,
    /// Point and line primitives: skipped.
    pub(crate) skipped_primitives: usize,
    /// Triangle strips and fans, converted to triangle lists.
    pub(crate) strips_and_fans: usize,
    /// Spot and directional lights: skipped (bdpm has isotropic point lights only).
    pub(crate) skipped_lights: usize,
    /// Nodes with a camera: ignored.
    pub(crate) skipped_cameras: usize,
    /// Texture coordinates of each triangle of `mesh`, in its order (zero where the
    /// material has no texture).
    pub(crate) texcoords: Vec<[Vec2; 3]>,
    /// Materials made from this file that use a base-colour texture.
    pub(crate) textured_materials: usize,
    /// Texture coordinates of each triangle of `mesh` for its material's emissive texture
    /// (zero where it has none); empty while no triangle's material has one, and then
    /// shorter than `mesh` by the triangles after the last that has.
    pub(crate) emission_texcoords: Vec<[Vec2; 3]>,
    /// Materials made from this file that emit with an emissive texture.
    pub(crate) emission_textured: usize,
    /// Materials made from this file with normal, occlusion or metallic-roughness textures,
    /// which are ignored.
    pub(crate) other_textures: usize,
    /// Triangle primitives without normals, shaded flat as glTF requires.
    pub(crate) flat_primitives: usize,
    /// What this file's materials became: mirrors, dielectrics, and what was approximated.
    pub(crate) mapped: Tally,
}

/// Where the file came from, for messages.
pub(crate) struct Origin<'a> {
    /// The file to open (already joined to the scene file's directory).
    pub(crate) path: &'a Path,
    /// The field that named it, such as `shape[2].file`.
    pub(crate) field: &'a str,
    /// The file as written in the scene file, used in generated material names.
    pub(crate) written: &'a Path,
}

impl Origin<'_> {
    fn err(&self, message: impl Into<String>) -> LoadError {
        LoadError::Gltf {
            path: self.path.to_path_buf(),
            field: self.field.to_string(),
            message: message.into(),
        }
    }
}

/// What the glTF files of one scene share while it loads: the decoded images, each decoded
/// once whatever the samplers, materials, files and `[[shape]]`s that show it, and the memory
/// budget every large allocation is checked against.
#[derive(Default)]
pub(crate) struct Assets {
    images: HashMap<ImageKey, Arc<TexelImage>>,
    pub(crate) budget: Budget,
}

impl Assets {
    pub(crate) fn new(budget: Budget) -> Assets {
        Assets {
            images: HashMap::new(),
            budget,
        }
    }

    /// Images decoded.
    pub(crate) fn decoded(&self) -> usize {
        self.images.len()
    }
}

/// Where an image's bytes come from: a file (canonical path), or a glTF file's own bytes
/// (its canonical path and the image's index: a bufferView or a data URI).
#[derive(Debug, PartialEq, Eq, Hash)]
enum ImageKey {
    File(PathBuf),
    Embedded(PathBuf, usize),
}

/// Loads every triangle primitive and KHR_lights_punctual point light of the default scene
/// (or the first scene, or every root node when there is no scene). `post` is applied after
/// each node's world matrix; `material` replaces every glTF material when given.
pub(crate) fn load_gltf(
    origin: &Origin<'_>,
    post: Mat4,
    material: Option<u32>,
    materials: &mut Materials,
    assets: &mut Assets,
) -> Result<GltfPart, LoadError> {
    let gltf = read_document(origin, &assets.budget)?;
    let buffers = load_buffers(origin, &gltf, &assets.budget)?;
    let doc = &gltf.document;
    let roots = root_nodes(doc);

    let mut part = GltfPart::default();
    let mut material_map: HashMap<usize, (u32, TexReads)> = HashMap::new();
    let mut images: HashMap<(usize, Wrap, Wrap), Arc<Texture>> = HashMap::new();
    let mut stack: Vec<(Node<'_>, Mat4, usize)> =
        roots.into_iter().rev().map(|n| (n, post, 0)).collect();
    let mut visits = 0;
    while let Some((node, parent, depth)) = stack.pop() {
        visits += 1;
        if depth > MAX_DEPTH || visits > MAX_VISITS {
            return Err(origin.err(format!(
                "node hierarchy deeper than {MAX_DEPTH} or larger than {MAX_VISITS} visits (a cycle?)"
            )));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(origin.err(format!("node {}: transform is not finite", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
                match prim.mode() {
                    Mode::Triangles => {}
                    Mode::TriangleStrip | Mode::TriangleFan => part.strips_and_fans += 1,
                    Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => {
                        part.skipped_primitives += 1;
                        continue;
                    }
                }
                let (m, tex_read) = match material {
                    Some(m) => (m, TexReads::default()),
                    None => {
                        let mut seen = Seen {
                            json: doc.as_json(),
                            assets: &mut *assets,
                            materials: &mut material_map,
                            images: &mut images,
                            part: &mut part,
                        };
                        primitive_material(origin, &prim, &buffers, &mut seen, materials)?
                    }
                };
                add_primitive(
                    origin, &what, &prim, &buffers, world, m, tex_read, &mut part,
                )?;
            }
        }
        if doc
            .as_json()
            .nodes
            .get(node.index())
            .is_some_and(|n| n.camera.is_some())
        {
            part.skipped_cameras += 1;
        }
        add_light(origin, doc, &node, world, &mut part)?;
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    Ok(part)
}

/// Reads and validates the glTF file (refused first if its size alone would not fit the
/// memory budget).
fn read_document(origin: &Origin<'_>, budget: &Budget) -> Result<gltf::Gltf, LoadError> {
    if let Ok(meta) = std::fs::metadata(origin.path) {
        budget
            .check(
                budget.textures(),
                meta.len(),
                "the file's bytes, read whole",
            )
            .map_err(|m| origin.err(format!("reading it {m}")))?;
    }
    let bytes = crate::files::read_regular(origin.path, crate::limits::MAX_GLTF_BYTES, "glTF file")
        .map_err(|e| origin.err(e.to_string()))?;
    let invalid = |e: gltf::Error| origin.err(format!("not a valid glTF 2.0 file: {}", brief(&e)));
    let raw = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| {
        if is_gltf_1(&bytes) {
            origin.err(
                "is a glTF 1.0 file; bdpm reads glTF 2.0 (convert it, e.g. import and export it with Blender)",
            )
        } else {
            invalid(e)
        }
    })?;
    let mut json = raw.document.into_json();
    check_required_extensions(&json).map_err(|m| origin.err(m))?;
    // gltf-json 1.4 parses KHR_materials_volume but leaves it off the list its validator
    // accepts in extensionsRequired; the check above has accepted it.
    json.extensions_required
        .retain(|e| e != "KHR_materials_volume");
    // gltf-json 1.4's validator indexes the accessor list with a primitive's POSITION index
    // before checking it (mesh.rs, primitive_validate_hook), so that case is checked first.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= json.accessors.len() {
                    return Err(origin.err(format!(
                        "not a valid glTF 2.0 file: meshes[{m}].primitives[{p}].attributes: {semantic:?} names accessor {}, which does not exist",
                        index.value()
                    )));
                }
            }
        }
    }
    Ok(gltf::Gltf {
        document: gltf::Document::from_json(json).map_err(invalid)?,
        blob: raw.blob,
    })
}

/// Extensions a file may list in `extensionsRequired` that the loader reads.
const READ_EXTENSIONS: [&str; 5] = [
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
];

/// One line for a file whose `extensionsRequired` names an extension bdpm cannot read, with
/// what to do; the validator would otherwise list every accessor the extension left empty
/// (a Draco file: 102 clauses).
fn check_required_extensions(json: &gltf::json::Root) -> Result<(), String> {
    for ext in &json.extensions_required {
        let advice = match ext.as_str() {
            "KHR_draco_mesh_compression" => "export without Draco",
            "EXT_meshopt_compression" => "export without mesh compression",
            "KHR_mesh_quantization" => "export with float positions and normals",
            "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif" => {
                "export PNG or JPEG textures"
            }
            e if READ_EXTENSIONS.contains(&e) => continue,
            _ => "export without it",
        };
        return Err(format!("uses {ext}, which bdpm does not decode; {advice}"));
    }
    Ok(())
}

/// Whether `bytes` are a glTF 1.x file: a GLB of container version 1, or JSON whose
/// `asset.version` is 1.x (or the number 1 of the drafts).
fn is_gltf_1(bytes: &[u8]) -> bool {
    if bytes.starts_with(b"glTF") {
        return bytes.get(4..8) == Some(&1u32.to_le_bytes()[..]);
    }
    use gltf::json::Value;
    // Drafts before 1.0 wrote the version as a number.
    let v = gltf::json::deserialize::from_slice::<Value>(bytes);
    match v.as_ref().ok().and_then(|v| v.pointer("/asset/version")) {
        Some(Value::String(s)) => s == "1" || s.starts_with("1."),
        Some(Value::Number(n)) => n.as_f64().is_some_and(|x| x < 2.0),
        _ => false,
    }
}

/// A glTF error in one short line: a validation error lists its first three problems and
/// how many more there are.
fn brief(e: &gltf::Error) -> String {
    match e {
        gltf::Error::Validation(list) if list.len() > 3 => {
            let first: Vec<String> = list[..3].iter().map(|(p, e)| format!("{p}: {e}")).collect();
            format!(
                "invalid glTF: {}; and {} more",
                first.join("; "),
                list.len() - 3
            )
        }
        other => other.to_string(),
    }
}

/// The nodes the walk starts from: the default scene's, or the first scene's, or every node
/// that is nobody's child when there is no scene.
fn root_nodes(doc: &gltf::Document) -> Vec<Node<'_>> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for node in doc.nodes() {
                for child in node.children() {
                    if let Some(flag) = is_child.get_mut(child.index()) {
                        *flag = true;
                    }
                }
            }
            doc.nodes()
                .filter(|n| !is_child.get(n.index()).copied().unwrap_or(false))
                .collect()
        }
    }
}

/// Adds the KHR_lights_punctual point light of `node` (at `world`'s origin) to `part`, or
/// counts a spot or directional light as skipped.
fn add_light(
    origin: &Origin<'_>,
    doc: &gltf::Document,
    node: &Node<'_>,
    world: Mat4,
    part: &mut GltfPart,
) -> Result<(), LoadError> {
    if let Some(light) = node_light(doc, node) {
        match light.type_ {
            Checked::Valid(LightType::Point) => {
                let flux = 4.0 * PI * light.intensity * Vec3::from_array(light.color);
                let position = world.transform_point3(Vec3::ZERO);
                if !(flux.is_finite() && flux.min_element() >= 0.0) {
                    return Err(origin.err(format!(
                            "node {}: point light has intensity {} and color {:?}; need finite values >= 0",
                            node.index(),
                            light.intensity,
                            light.color
                        )));
                }
                if !position.is_finite() {
                    return Err(origin.err(format!(
                        "node {}: light position is not finite",
                        node.index()
                    )));
                }
                part.lights.push(PointLight { position, flux });
            }
            _ => part.skipped_lights += 1,
        }
    }
    Ok(())
}

/// The KHR_lights_punctual light a node carries, read from the JSON directly: the crate's
/// `Node::light` unwraps indices and spot parameters that a malformed file may lack.
fn node_light<'a>(
    doc: &'a gltf::Document,
    node: &Node<'_>,
) -> Option<&'a gltf::json::extensions::scene::khr_lights_punctual::Light> {
    let json = doc.as_json();
    let index = json
        .nodes
        .get(node.index())?
        .extensions
        .as_ref()?
        .khr_lights_punctual
        .as_ref()?
        .light
        .value();
    json.extensions
        .as_ref()?
        .khr_lights_punctual
        .as_ref()?
        .lights
        .get(index)
}

/// What one file's walk has met so far: its materials (scene index and the texture-coordinate
/// sets of their base-colour and emissive textures), its decoded images, and the counts in
/// `part`.
struct Seen<'a> {
    /// The file's JSON, read directly where the `gltf` crate's accessors would panic.
    json: &'a gltf::json::Root,
    assets: &'a mut Assets,
    materials: &'a mut HashMap<usize, (u32, TexReads)>,
    images: &'a mut HashMap<(usize, Wrap, Wrap), Arc<Texture>>,
    part: &'a mut GltfPart,
}

/// The scene material of a primitive and the TEXCOORD sets its textures read: the TOML
/// material of the same name if there is one (used as it is, without a texture), otherwise
/// the model `gltf_material::map` makes of it (a mirror, a dielectric, or Lambert with
/// kd = baseColorFactor × the base-colour texture if it has one; any of them emitting
/// emissiveFactor × emissiveStrength × the emissive texture if it has one), or the shared
/// default (kd = 0.8) when the primitive has none. Materials are counted once, when first met.
fn primitive_material(
    origin: &Origin<'_>,
    prim: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    seen: &mut Seen<'_>,
    materials: &mut Materials,
) -> Result<(u32, TexReads), LoadError> {
    let mat = prim.material();
    let Some(index) = mat.index() else {
        return Ok((materials.gltf_default()?, TexReads::default()));
    };
    if let Some(&m) = seen.materials.get(&index) {
        return Ok(m);
    }
    let m = if let Some(m) = mat.name().and_then(|name| materials.lookup(name)) {
        (m, TexReads::default())
    } else {
        let pbr = mat.pbr_metallic_roughness();
        if mat.normal_texture().is_some()
            || mat.occlusion_texture().is_some()
            || pbr.metallic_roughness_texture().is_some()
        {
            seen.part.other_textures += 1;
        }
        let name = match mat.name() {
            Some(name) => name.to_string(),
            None => format!("gltf:{}#{index}", origin.written.display()),
        };
        let (json, tally) = (seen.json, &mut seen.part.mapped);
        let made = make(json, index, &name, origin.written, materials, tally);
        let (made, (emission, two_sided)) = made.map_err(|m| origin.err(m))?;
        let kd = match made {
            Made::Lambert(kd) => kd,
            Made::Delta(m) => {
                materials.set_emission(m, emission, two_sided);
                let reads = TexReads {
                    base: None,
                    emissive: emissive_texture(origin, &mat, m, buffers, seen, materials)?,
                };
                let _ = seen.materials.insert(index, (m, reads));
                return Ok((m, reads));
            }
        };
        let m = materials
            .add_lambert(name, kd)
            .map_err(|e| origin.err(format!("material {index}: {e}")))?;
        materials.set_emission(m, emission, two_sided);
        let base = match pbr.base_color_texture() {
            Some(info) => {
                let texture =
                    material_texture(origin, index, &info.texture(), BASE, buffers, seen)?;
                materials.set_texture(m, texture);
                seen.part.textured_materials += 1;
                Some(TexRead::of(&info))
            }
            None => None,
        };
        let emissive = emissive_texture(origin, &mat, m, buffers, seen, materials)?;
        (m, TexReads { base, emissive })
    };
    let _ = seen.materials.insert(index, m);
    Ok(m)
}

/// How a primitive's texture coordinates are read for each of its material's textures.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TexReads {
    /// For the base-colour texture.
    base: Option<TexRead>,
    /// For the emissive texture (only where the material emits).
    emissive: Option<TexRead>,
}

/// The emissive texture of glTF material `mat` (scene material `m`), if it has one and emits:
/// decoded as base colour is (sRGB, glTF 2.0 §3.9.5), given to the scene material, counted;
/// the texture coordinates its reference reads.
fn emissive_texture(
    origin: &Origin<'_>,
    mat: &gltf::Material<'_>,
    m: u32,
    buffers: &[Vec<u8>],
    seen: &mut Seen<'_>,
    materials: &mut Materials,
) -> Result<Option<TexRead>, LoadError> {
    let Some(info) = mat.emissive_texture() else {
        return Ok(None);
    };
    if !materials.emits(m) {
        // Le = emissiveFactor × texture: a zero factor leaves nothing to texture.
        return Ok(None);
    }
    let index = mat.index().unwrap_or_default();
    let texture = material_texture(origin, index, &info.texture(), EMISSIVE, buffers, seen)?;
    materials.set_emission_texture(m, texture);
    seen.part.emission_textured += 1;
    Ok(Some(TexRead::of(&info)))
}

/// The names of the two textures read, for messages.
const BASE: &str = "base-colour";
const EMISSIVE: &str = "emissive";

/// How a primitive's texture coordinates are read for one of its material's textures: the
/// TEXCOORD set, and the KHR_texture_transform of the texture reference, if any.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TexRead {
    set: u32,
    /// uv ↦ T·R·S·uv of KHR_texture_transform (offset, counter-clockwise rotation, scale).
    transform: Option<Affine2>,
}

impl TexRead {
    fn of(info: &gltf::texture::Info<'_>) -> TexRead {
        let ext = info.texture_transform();
        let transform = ext.as_ref().map(|t| {
            let ([sx, sy], r) = (t.scale(), t.rotation());
            let (sin, cos) = r.sin_cos();
            // The extension's matrix translation · rotation · scale, with rotation
            // [[cos, sin], [−sin, cos]] as it writes it (rows).
            let linear = Mat2::from_cols(
                Vec2::new(cos * sx, -sin * sx),
                Vec2::new(sin * sy, cos * sy),
            );
            Affine2::from_mat2_translation(linear, Vec2::from_array(t.offset()))
        });
        TexRead {
            set: ext.and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord()),
            transform,
        }
    }
}

/// The decoded image of a base-colour or emissive texture (`kind`, for messages) with its
/// sampler's wrap modes (decoded once per image and sampler, sRGB as glTF asks of both). The
/// image is a PNG or JPEG file next to the glTF file, a base64 `data:` URI, or a bufferView
/// (GLB).
fn material_texture(
    origin: &Origin<'_>,
    material: usize,
    texture: &gltf::Texture<'_>,
    kind: &str,
    buffers: &[Vec<u8>],
    seen: &mut Seen<'_>,
) -> Result<Arc<Texture>, LoadError> {
    let wrap = |w: gltf::texture::WrappingMode| match w {
        gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
    };
    let sampler = texture.sampler();
    let (wrap_u, wrap_v) = (wrap(sampler.wrap_s()), wrap(sampler.wrap_t()));
    let image = texture.source();
    let key_per_file = (image.index(), wrap_u, wrap_v);
    if let Some(t) = seen.images.get(&key_per_file) {
        return Ok(Arc::clone(t));
    }
    let what = format!(
        "material {material}: {kind} texture {} (image {})",
        texture.index(),
        image.index()
    );
    let err = |m: String| origin.err(format!("{what}: {m}"));
    let key = image_key(origin, seen.json, image.index()).map_err(err)?;
    let texels = match seen.assets.images.get(&key) {
        Some(texels) => Arc::clone(texels),
        None => {
            let bytes = image_bytes(origin, seen.json, image.index(), buffers, &what)?;
            let header = crate::image::header(&bytes).map_err(err)?;
            // Before the decoder allocates: the texels kept so far and this file's buffers
            // are held, so a texture too large for the limit is refused here, not in the
            // allocation.
            let held =
                seen.assets.budget.textures() + buffers.iter().map(|b| b.len() as u64).sum::<u64>();
            seen.assets
                .budget
                .check(
                    held,
                    header.decode_bytes,
                    "3 bytes a texel kept, and the decoder's buffers",
                )
                .map_err(|m| {
                    err(format!(
                        "decoding its {}×{} texels {m}",
                        header.width, header.height
                    ))
                })?;
            let decoded = crate::image::decode(&bytes).map_err(err)?;
            drop(bytes);
            let texels = Arc::new(
                TexelImage::srgb8(decoded.width, decoded.height, decoded.rgb)
                    .map_err(|e| err(e.to_string()))?,
            );
            seen.assets.budget.keep_texels(texels.bytes());
            let _ = seen.assets.images.insert(key, Arc::clone(&texels));
            texels
        }
    };
    let texture = Arc::new(Texture::with_image(texels, wrap_u, wrap_v));
    let _ = seen.images.insert(key_per_file, Arc::clone(&texture));
    Ok(texture)
}

/// The [`ImageKey`] of image `index` of the glTF file `origin`: a file named by its uri
/// (confined to the glTF file's directory), else the glTF file's own bytes.
fn image_key(
    origin: &Origin<'_>,
    json: &gltf::json::Root,
    index: usize,
) -> Result<ImageKey, String> {
    let canonical = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let image = json
        .images
        .get(index)
        .ok_or_else(|| format!("image {index} does not exist"))?;
    match (&image.buffer_view, &image.uri) {
        (None, Some(uri)) if !uri.starts_with("data:") => {
            let dir = origin.path.parent().unwrap_or(Path::new(""));
            Ok(ImageKey::File(canonical(&crate::files::confined_uri(
                dir, uri,
            )?)))
        }
        _ => Ok(ImageKey::Embedded(canonical(origin.path), index)),
    }
}

/// The encoded bytes of image `index`: a bufferView's bytes (GLB, or any buffer), a base64
/// `data:` URI, or a PNG or JPEG file next to the glTF file. Read from the JSON directly: the
/// `gltf` crate's `Image::source` panics on an image with a bufferView but no mimeType, and on
/// one with neither a bufferView nor a uri. The mimeType is not needed (images are recognised
/// by their first bytes).
fn image_bytes(
    origin: &Origin<'_>,
    json: &gltf::json::Root,
    index: usize,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<u8>, LoadError> {
    let err = |m: String| origin.err(format!("{what}: {m}"));
    let image = json
        .images
        .get(index)
        .ok_or_else(|| err(format!("image {index} does not exist")))?;
    if let Some(view) = &image.buffer_view {
        let v = view.value();
        let view = json
            .buffer_views
            .get(v)
            .ok_or_else(|| err(format!("bufferView {v} does not exist")))?;
        let b = view.buffer.value();
        let data = buffers
            .get(b)
            .ok_or_else(|| err(format!("bufferView {v}: buffer {b} does not exist")))?;
        let start = view.byte_offset.map_or(0, |o| o.0) as usize;
        return match start.checked_add(view.byte_length.0 as usize) {
            Some(end) if end <= data.len() => Ok(data[start..end].to_vec()),
            _ => Err(err(format!(
                "bufferView {v} reaches past the end of buffer {b} ({} bytes)",
                data.len()
            ))),
        };
    }
    let Some(uri) = &image.uri else {
        return Err(err(
            "has neither a uri nor a bufferView, so there are no image bytes to read".into(),
        ));
    };
    if uri.starts_with("data:") {
        let (header, payload) = uri
            .split_once(',')
            .ok_or_else(|| err("malformed data URI (no comma)".into()))?;
        if !header.ends_with(";base64") {
            return Err(err("only base64 data URIs are supported".into()));
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| err(format!("bad base64 in data URI: {e}")));
    }
    let dir = origin.path.parent().unwrap_or(Path::new(""));
    let file = crate::files::confined_uri(dir, uri).map_err(err)?;
    crate::files::read_regular(&file, crate::limits::MAX_GLTF_BYTES, "texture image").map_err(|e| {
        LoadError::Gltf {
            path: file.clone(),
            field: format!("{}, {what} of {}", origin.field, origin.path.display()),
            message: e.to_string(),
        }
    })
}

/// Appends one triangle primitive, transformed by `world`, to `part`, with the texture
/// coordinates `reads` asks for when its material has textures (zero when the primitive
/// lacks that set).
#[allow(clippy::too_many_arguments)]
fn add_primitive(
    origin: &Origin<'_>,
    what: &str,
    prim: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    world: Mat4,
    material: u32,
    reads: TexReads,
    part: &mut GltfPart,
) -> Result<(), LoadError> {
    let err = |m: String| origin.err(format!("{what}: {m}"));
    let get = |b: gltf::Buffer<'_>| buffers.get(b.index()).map(Vec::as_slice);
    let reader = prim.reader(get);

    let pos_acc = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| err("has no POSITION attribute".into()))?;
    check_accessor(&pos_acc, &[DataType::F32], Dimensions::Vec3, buffers)
        .map_err(|m| err(format!("POSITION: {m}")))?;
    let positions: Vec<Vec3> = if pos_acc.count() == 0 {
        Vec::new()
    } else {
        reader
            .read_positions()
            .ok_or_else(|| err("POSITION cannot be read".into()))?
            .map(|p| world.transform_point3(Vec3::from_array(p)))
            .collect()
    };
    if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
        return Err(err(format!(
            "vertex {k} is not finite (after the node transforms)"
        )));
    }

    let normals = read_normals(prim, buffers, world, positions.len(), &err)?;
    let texcoords = read_texcoords(prim, buffers, reads.base, positions.len(), &err)?;
    let emission_texcoords = read_texcoords(prim, buffers, reads.emissive, positions.len(), &err)?;
    let indices = triangle_list(
        prim.mode(),
        read_indices(prim, buffers, positions.len(), &err)?,
    );
    if !indices.len().is_multiple_of(3) {
        return Err(err(format!(
            "{} indices is not a multiple of 3",
            indices.len()
        )));
    }
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(err(format!(
            "index {bad} is out of range ({} vertices)",
            positions.len()
        )));
    }

    let mesh = &mut part.mesh;
    let base = mesh.positions.len();
    if base + positions.len() > u32::MAX as usize {
        return Err(err("too many vertices (more than 2^32 in total)".into()));
    }
    let base = base as u32;
    // A mirroring transform turns counter-clockwise into clockwise; glTF asks to keep the
    // front face, so the winding is reversed.
    let mirror = Mat3::from_mat4(world).determinant() < 0.0;
    let corners = |uv: &[Vec2], t: &[u32]| {
        let at = |i: u32| uv.get(i as usize).copied().unwrap_or(Vec2::ZERO);
        let (ta, tb, tc) = (at(t[0]), at(t[1]), at(t[2]));
        if mirror { [ta, tc, tb] } else { [ta, tb, tc] }
    };
    if reads.emissive.is_some() {
        // Kept from the first triangle with an emissive texture on: zero for those before.
        part.emission_texcoords
            .resize(mesh.indices.len(), [Vec2::ZERO; 3]);
    }
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] + base, t[1] + base, t[2] + base);
        mesh.indices
            .push(if mirror { [a, c, b] } else { [a, b, c] });
        mesh.materials.push(material);
        part.texcoords.push(corners(&texcoords, t));
        if reads.emissive.is_some() {
            part.emission_texcoords
                .push(corners(&emission_texcoords, t));
        }
    }
    if normals.is_empty() {
        part.flat_primitives += 1;
        if !mesh.normals.is_empty() {
            mesh.normals
                .extend(std::iter::repeat_n(Vec3::ZERO, positions.len()));
        }
    } else {
        if mesh.normals.len() < mesh.positions.len() {
            mesh.normals.resize(mesh.positions.len(), Vec3::ZERO);
        }
        mesh.normals.extend_from_slice(&normals);
    }
    mesh.positions.extend_from_slice(&positions);
    Ok(())
}

/// A primitive's indices as a triangle list. Strips and fans become lists (glTF 2.0
/// §3.7.2.1): strip triangle i is (v[i], v[i+1+i%2], v[i+2-i%2]), which keeps every
/// triangle's winding; fan triangle i is (v[i+1], v[i+2], v[0]). Degenerate triangles that
/// stitch strips have zero area and are left out of the BVH like any other.
fn triangle_list(mode: Mode, indices: Vec<u32>) -> Vec<u32> {
    match mode {
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .flat_map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan => (1..indices.len().saturating_sub(1))
            .flat_map(|i| [indices[i], indices[i + 1], indices[0]])
            .collect(),
        _ => indices,
    }
}

/// The primitive's NORMAL attribute transformed by `world`'s inverse transpose and
/// normalised (zero where not finite: flat); empty when it has none.
fn read_normals(
    prim: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    world: Mat4,
    vertices: usize,
    err: &dyn Fn(String) -> LoadError,
) -> Result<Vec<Vec3>, LoadError> {
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    Ok(match prim.get(&Semantic::Normals) {
        Some(acc) if acc.count() > 0 => {
            check_accessor(&acc, &[DataType::F32], Dimensions::Vec3, buffers)
                .map_err(|m| err(format!("NORMAL: {m}")))?;
            if acc.count() != vertices {
                return Err(err(format!(
                    "{} normals for {} positions",
                    acc.count(),
                    vertices
                )));
            }
            // Normals transform by the inverse transpose; a singular matrix flattens the mesh,
            // whose triangles are then degenerate anyway, so zero (= flat) normals serve.
            let linear = Mat3::from_mat4(world);
            let normal_matrix = if linear.determinant() != 0.0 {
                linear.inverse().transpose()
            } else {
                Mat3::ZERO
            };
            let read = reader
                .read_normals()
                .ok_or_else(|| err("NORMAL cannot be read".into()))?;
            read.map(|n| {
                let n = normal_matrix * Vec3::from_array(n);
                if n.is_finite() {
                    n.normalize_or_zero()
                } else {
                    Vec3::ZERO
                }
            })
            .collect()
        }
        _ => Vec::new(),
    })
}

/// The primitive's texture coordinates for `tex_read` (its set, transformed); empty without
/// a texture or when the primitive lacks the set.
fn read_texcoords(
    prim: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    tex_read: Option<TexRead>,
    vertices: usize,
    err: &dyn Fn(String) -> LoadError,
) -> Result<Vec<Vec2>, LoadError> {
    let Some(TexRead { set, transform }) = tex_read else {
        return Ok(Vec::new());
    };
    let acc = match prim.get(&Semantic::TexCoords(set)) {
        Some(acc) if acc.count() > 0 => acc,
        _ => return Ok(Vec::new()),
    };
    check_accessor(
        &acc,
        &[DataType::F32, DataType::U8, DataType::U16],
        Dimensions::Vec2,
        buffers,
    )
    .map_err(|m| err(format!("TEXCOORD_{set}: {m}")))?;
    if acc.count() != vertices {
        return Err(err(format!(
            "{} texture coordinates for {} positions",
            acc.count(),
            vertices
        )));
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let uv = reader
        .read_tex_coords(set)
        .ok_or_else(|| err(format!("TEXCOORD_{set} cannot be read")))?
        .into_f32()
        .map(Vec2::from_array);
    Ok(match transform {
        Some(t) => uv.map(|uv| t.transform_point2(uv)).collect(),
        None => uv.collect(),
    })
}

/// The primitive's indices as given (`0..vertices` when it has none), before strips and fans
/// are turned into lists.
fn read_indices(
    prim: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    vertices: usize,
    err: &dyn Fn(String) -> LoadError,
) -> Result<Vec<u32>, LoadError> {
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    Ok(match prim.indices() {
        Some(acc) => {
            check_accessor(
                &acc,
                &[DataType::U8, DataType::U16, DataType::U32],
                Dimensions::Scalar,
                buffers,
            )
            .map_err(|m| err(format!("indices: {m}")))?;
            if acc.count() == 0 {
                Vec::new()
            } else {
                let read = reader
                    .read_indices()
                    .ok_or_else(|| err("indices cannot be read".into()))?;
                read.into_u32().collect()
            }
        }
        None => (0..vertices as u32).collect(),
    })
}

/// Checks that reading `acc` stays inside its buffer and has the expected layout, so the
/// `gltf` reader can neither panic nor read garbage.
fn check_accessor(
    acc: &Accessor<'_>,
    types: &[DataType],
    dims: Dimensions,
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    if acc.sparse().is_some() {
        return Err(format!(
            "accessor {} is sparse, which is not supported",
            acc.index()
        ));
    }
    // Integer components are read only where they are normalized (texture coordinates);
    // everywhere else a normalized accessor is quantized data, which is not supported.
    let integer_ok =
        acc.normalized() == (acc.data_type() != DataType::F32 && dims == Dimensions::Vec2);
    if !types.contains(&acc.data_type()) || acc.dimensions() != dims || !integer_ok {
        return Err(format!(
            "accessor {} is {:?} {:?}{}; expected {:?} of {:?}",
            acc.index(),
            acc.dimensions(),
            acc.data_type(),
            if acc.normalized() {
                " (normalized)"
            } else {
                ""
            },
            dims,
            types
        ));
    }
    if acc.count() == 0 {
        return Ok(());
    }
    let view = acc
        .view()
        .ok_or_else(|| format!("accessor {} has no bufferView", acc.index()))?;
    let size = acc.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "bufferView {} has stride {stride}, shorter than its {size}-byte elements",
            view.index()
        ));
    }
    let end = stride
        .checked_mul(acc.count() - 1)
        .and_then(|x| x.checked_add(size))
        .and_then(|x| x.checked_add(acc.offset()));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "accessor {} reaches past the end of bufferView {}",
            acc.index(),
            view.index()
        ));
    }
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    if view
        .offset()
        .checked_add(view.length())
        .is_none_or(|end| end > buffer_len)
    {
        return Err(format!(
            "bufferView {} reaches past the end of buffer {}",
            view.index(),
            view.buffer().index()
        ));
    }
    Ok(())
}

/// Resolves every buffer: the GLB binary chunk, a base64 `data:` URI, or a file relative to
/// the glTF file.
fn load_buffers(
    origin: &Origin<'_>,
    gltf: &gltf::Gltf,
    budget: &Budget,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let mut out: Vec<Vec<u8>> = Vec::new();
    for buffer in gltf.buffers() {
        let i = buffer.index();
        // Held until the file's primitives are read: refused before the read if, with the
        // texels kept and the buffers before it, it would not fit.
        let held = budget.textures() + out.iter().map(|b| b.len() as u64).sum::<u64>();
        budget
            .check(
                held,
                buffer.length() as u64,
                "held while the file's meshes are read",
            )
            .map_err(|m| origin.err(format!("buffer {i} ({} bytes) {m}", buffer.length())))?;
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                origin.err(format!(
                    "buffer {i} refers to a GLB binary chunk, which is missing"
                ))
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (header, payload) = uri
                    .split_once(',')
                    .ok_or_else(|| origin.err(format!("buffer {i}: malformed data URI")))?;
                if !header.ends_with(";base64") {
                    return Err(
                        origin.err(format!("buffer {i}: only base64 data URIs are supported"))
                    );
                }
                base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| origin.err(format!("buffer {i}: bad base64 in data URI: {e}")))?
            }
            gltf::buffer::Source::Uri(uri) => {
                let dir = origin.path.parent().unwrap_or(Path::new(""));
                let file: PathBuf = crate::files::confined_uri(dir, uri)
                    .map_err(|e| origin.err(format!("buffer {i}: {e}")))?;
                // Only the declared bytes are needed; a longer file is read no further.
                let limit = (buffer.length() as u64).min(crate::limits::MAX_GLTF_BYTES);
                crate::files::read_regular(&file, crate::limits::MAX_GLTF_BYTES, "glTF buffer")
                    .map(|mut bytes| {
                        bytes.truncate(limit as usize);
                        bytes
                    })
                    .map_err(|e| LoadError::Gltf {
                        path: file.clone(),
                        field: format!("{}, buffer {i} of {}", origin.field, origin.path.display()),
                        message: e.to_string(),
                    })?
            }
        };
        if data.len() < buffer.length() {
            return Err(origin.err(format!(
                "buffer {i} has {} bytes but declares byteLength {}",
                data.len(),
                buffer.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}
