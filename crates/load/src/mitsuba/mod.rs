//! Mitsuba 3 XML scenes (`bdpm render scene.xml`): the inverse of bdpm-export's mapping,
//! and what else of Mitsuba's format bdpm can render (docs/scene-format.md, "Import from
//! Mitsuba 3"). Parsed with roxmltree, whose nodes keep their place in the text, so that
//! every error and warning names the file, the line and the element.
//!
//! What maps: `<default>` and `$name`, `<path>`, `<include>`; shapes `obj`, `ply`,
//! `rectangle`, `cube`, `sphere`, `disk`, `shapegroup`/`instance`; transforms; BSDFs
//! (see `bsdf`); `point` emitters and `area` emitters nested in shapes; `bitmap` textures as a
//! diffuse reflectance or an area emitter's radiance (see `bitmap`), read through the mesh
//! files' texture coordinates; a `perspective` sensor with its film size. Everything else
//! is refused with a one-line error, or ignored with a warning where it changes nothing bdpm
//! renders (the integrator, the sampler, the film's filter).

mod bitmap;
mod bsdf;
mod doc;
mod sensor;
mod shape;
mod transform;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use bdpm_geometry::{Geometry, TriangleMesh};
use bdpm_scene::{EmissionTextures, PointLight, Scene, SceneTextures};
use bdpm_settings::RenderSettings;
use glam::Vec2;
use roxmltree::{Document, Node};

use self::bitmap::{Images, Loader};
use self::bsdf::{Bsdf, Named, Reader};
use self::doc::{Xml, elements};
use crate::build::{Shapes, geometry_error, scene_error};
use crate::ctx::Ctx;
use crate::materials::Materials;
use crate::memory::Budget;
use crate::{LoadError, LoadOptions, LoadReport, LoadedScene, files, limits};

/// Deepest chain of `<include>`s.
const MAX_INCLUDE_DEPTH: usize = 8;

/// The scene as it is read, element by element.
pub(crate) struct State {
    search: Vec<PathBuf>,
    named: Named,
    groups: HashMap<String, TriangleMesh>,
    materials: Materials,
    default_material: Option<u32>,
    /// Emitting copies of materials by (material, radiance bits, the radiance texture's
    /// address or 0).
    emitting: HashMap<(u32, [u32; 3], usize), u32>,
    lights: Vec<PointLight>,
    shapes: Shapes,
    budget: Budget,
    sensor: Option<sensor::Sensor>,
    warnings: Vec<String>,
    files: Vec<PathBuf>,
    builtin_triangles: u64,
    images: Images,
}

/// What reading a bitmap takes from the [`State`], and where warnings go, borrowed apart.
pub(crate) struct Reading<'a> {
    pub(crate) bitmaps: Loader<'a>,
    pub(crate) warnings: &'a mut Vec<String>,
}

/// Loads the Mitsuba scene `text`, read from `display_path` in `base_dir`.
pub(crate) fn load(
    text: &str,
    base_dir: &Path,
    display_path: &Path,
    options: &LoadOptions,
) -> Result<LoadedScene, LoadError> {
    let mut st = State {
        search: Vec::new(),
        named: Named::new(),
        groups: HashMap::new(),
        materials: Materials::with_capacity(8),
        default_material: None,
        emitting: HashMap::new(),
        lights: Vec::new(),
        shapes: Shapes::default(),
        budget: Budget::new(options.memory_limit.clone()),
        sensor: None,
        warnings: Vec::new(),
        files: Vec::new(),
        builtin_triangles: 0,
        images: Images::default(),
    };
    st.file(text, display_path, base_dir, &HashMap::new(), 0)?;
    st.finish(display_path)
}

/// The document of `text`, or the parser's message with its line and column.
fn parse<'t>(text: &'t str, path: &Path) -> Result<Document<'t>, LoadError> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: 10_000_000,
    };
    Document::parse_with_options(text, options).map_err(|e| {
        let pos = e.pos();
        LoadError::Syntax {
            path: path.to_path_buf(),
            line: pos.row as usize,
            column: pos.col as usize,
            message: format!("malformed XML: {e}"),
        }
    })
}

impl State {
    /// Reads one file (the scene or an included one) into the state.
    fn file(
        &mut self,
        text: &str,
        path: &Path,
        dir: &Path,
        inherited: &HashMap<String, String>,
        depth: usize,
    ) -> Result<(), LoadError> {
        let doc = parse(text, path)?;
        let root = doc.root_element();
        let mut defaults = inherited.clone();
        let plain = HashMap::new();
        let x = Xml {
            file: path,
            defaults: &plain,
        };
        if root.tag_name().name() != "scene" {
            return Err(x.err(root, "the root element must be <scene version=\"3.x.x\">"));
        }
        let version = x.need(root, "version")?;
        if !(version.starts_with("2.") || version.starts_with("3.")) {
            return Err(x.err(
                root,
                format!(
                    "version \"{version}\": bdpm reads Mitsuba 2 and 3 scenes (2.x.x or 3.x.x)"
                ),
            ));
        }
        for d in elements(root).filter(|c| c.tag_name().name() == "default") {
            let name = x.need(d, "name")?;
            let value = x.need(d, "value")?;
            // The including file's value (or the command line's, in Mitsuba) wins.
            defaults.entry(name).or_insert(value);
        }
        let x = Xml {
            file: path,
            defaults: &defaults,
        };
        for c in elements(root) {
            self.element(&x, dir, c, depth)?;
        }
        Ok(())
    }

    /// One top-level element.
    fn element(
        &mut self,
        x: &Xml<'_>,
        dir: &Path,
        c: Node<'_, '_>,
        depth: usize,
    ) -> Result<(), LoadError> {
        match c.tag_name().name() {
            "default" => {}
            "path" => {
                let value = x.need(c, "value")?;
                self.search.push(dir.join(value));
            }
            "include" => self.include(x, dir, c, depth)?,
            "integrator" => self.warnings.push(x.warn(c, "ignored: bdpm renders with its own method (bidirectional photon mapping, --mode)")),
            "sensor" if self.sensor.is_some() => self.warnings.push(x.warn(c, "a second sensor is ignored: bdpm renders the first")),
            "sensor" => self.sensor = Some(sensor::sensor(x, c, &mut self.warnings)?),
            "emitter" => {
                let light = sensor::emitter(x, c, &mut self.warnings)?;
                self.lights.push(light);
            }
            "bsdf" => {
                let Some(id) = x.attr(c, "id")? else {
                    self.warnings.push(x.warn(c, "a top-level BSDF without id is never used"));
                    return Ok(());
                };
                let (index, bsdf) = self.bsdf(x, dir, c, &id)?;
                self.named.insert(id, (index, bsdf));
            }
            "texture" => {
                let Some(id) = x.attr(c, "id")? else {
                    self.warnings.push(x.warn(c, "a top-level texture without id is never used"));
                    return Ok(());
                };
                let mut r = self.loader(dir);
                let bitmap = r.bitmaps.read(x, c, r.warnings)?;
                self.images.name(id, bitmap);
            }
            "shape" => {
                if let Some(part) = shape::shape(self, x, dir, c)? {
                    self.add_shape(x, c, part)?;
                }
            }
            other => return Err(x.err(c, format!("<{other}> is not supported (bdpm reads default, path, include, integrator, sensor, emitter, bsdf, texture and shape)"))),
        }
        Ok(())
    }

    /// `<include filename=…>`: the file's elements as if written here.
    fn include(
        &mut self,
        x: &Xml<'_>,
        dir: &Path,
        c: Node<'_, '_>,
        depth: usize,
    ) -> Result<(), LoadError> {
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(x.err(
                c,
                format!("more than {MAX_INCLUDE_DEPTH} nested includes (a cycle?)"),
            ));
        }
        let name = x.need(c, "filename")?;
        let path = self.resolve(dir, &name);
        let bytes = files::read_regular(&path, limits::MAX_SCENE_FILE_BYTES, "included file")
            .map_err(|e| x.err(c, format!("{}: {e}", path.display())))?;
        let text = String::from_utf8(bytes)
            .map_err(|e| x.err(c, format!("{}: not UTF-8 text: {e}", path.display())))?;
        let sub_dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        self.files.push(path.clone());
        self.file(&text, &path, &sub_dir, x.defaults, depth + 1)
    }

    /// The bitmap reader for files named in `dir`, and the warnings, borrowed from the state.
    pub(crate) fn loader<'a>(&'a mut self, dir: &'a Path) -> Reading<'a> {
        Reading {
            bitmaps: Loader {
                dir,
                search: &self.search,
                budget: &mut self.budget,
                images: &mut self.images,
                files: &mut self.files,
            },
            warnings: &mut self.warnings,
        }
    }

    /// A named BSDF (file names in it relative to `dir`), added to the scene's materials
    /// under its id, with its reflectance texture if it has one.
    fn bsdf(
        &mut self,
        x: &Xml<'_>,
        dir: &Path,
        node: Node<'_, '_>,
        name: &str,
    ) -> Result<(u32, Bsdf), LoadError> {
        let mut loader = Loader {
            dir,
            search: &self.search,
            budget: &mut self.budget,
            images: &mut self.images,
            files: &mut self.files,
        };
        let bsdf = Reader {
            x,
            named: &self.named,
            warnings: &mut self.warnings,
            bitmaps: Some(&mut loader),
        }
        .read(node)?;
        let model = bsdf::material(x, node, &bsdf)?;
        let index = self.materials.add_delta(name.to_string(), model);
        if let Bsdf::Smooth {
            texture: Some(t), ..
        } = &bsdf
        {
            self.materials.set_texture(index, Arc::clone(t));
        }
        Ok((index, bsdf))
    }

    /// Appends a shape's triangles, with the texture coordinates of those whose material has
    /// a reflectance or an emissive texture (a shape without texture coordinates reads its
    /// textures at (0, 0), warned, where Mitsuba would use its own parameterisation).
    fn add_shape(
        &mut self,
        x: &Xml<'_>,
        node: Node<'_, '_>,
        part: shape::Part,
    ) -> Result<(), LoadError> {
        let shape::Part { mesh, uv } = part;
        let before = self.shapes.mesh.indices.len();
        let corners = |t: &[u32; 3]| match uv.is_empty() {
            true => [Vec2::ZERO; 3],
            false => t.map(|i| uv[i as usize]),
        };
        let (mut base, mut emissive) = (Vec::new(), Vec::new());
        let mut missing = false;
        for (t, &m) in mesh.indices.iter().zip(&mesh.materials) {
            let (b, e) = self.materials.textured(m);
            missing |= (b || e) && uv.is_empty();
            base.push(if b { corners(t) } else { [Vec2::ZERO; 3] });
            if e {
                emissive.resize(base.len() - 1, [Vec2::ZERO; 3]);
                emissive.push(corners(t));
            }
        }
        if missing {
            self.warnings.push(x.warn(node, "the shape has no texture coordinates: bdpm reads its textures at (0, 0) (Mitsuba uses the shape's own parameterisation); give it a mesh file with texture coordinates"));
        }
        self.shapes.append(&Ctx { file: x.file }, mesh)?;
        self.shapes.texcoords.truncate(before);
        self.shapes.texcoords.extend_from_slice(&base);
        if !emissive.is_empty() {
            let t = &mut self.shapes.emission_texcoords;
            t.resize(before, [Vec2::ZERO; 3]);
            t.extend_from_slice(&emissive);
        }
        Ok(())
    }

    /// The material of a shape ([`Self::bsdf_of_shape`]); with `emission` (the radiance of
    /// the shape's area emitter, W·m⁻²·sr⁻¹ per channel) a copy of it that emits from the
    /// front side, as Mitsuba's area emitter does whatever the BSDF (`twosided` included),
    /// one copy per material and radiance; a shape's own nested BSDF is given the emission
    /// in place.
    fn shape_material(
        &mut self,
        x: &Xml<'_>,
        dir: &Path,
        node: Node<'_, '_>,
        emission: Option<shape::Emission>,
    ) -> Result<u32, LoadError> {
        let (m, own) = self.bsdf_of_shape(x, dir, node)?;
        let Some((le, texture)) = emission else {
            return Ok(m);
        };
        let target = if own {
            self.materials.set_emission(m, le, false);
            m
        } else {
            let address = texture.as_ref().map_or(0, |t| Arc::as_ptr(t) as usize);
            let key = (m, le.to_array().map(f32::to_bits), address);
            if let Some(&copy) = self.emitting.get(&key) {
                return Ok(copy);
            }
            let copy = self.materials.add_emitting_copy(m, le);
            self.emitting.insert(key, copy);
            copy
        };
        if let Some(t) = texture {
            self.materials.set_emission_texture(target, t);
        }
        Ok(target)
    }

    /// The material of a shape: its nested `<bsdf>` (then `true`: the shape's own) or
    /// `<ref id=…>`, else Mitsuba's default (diffuse of reflectance 0.5).
    fn bsdf_of_shape(
        &mut self,
        x: &Xml<'_>,
        dir: &Path,
        node: Node<'_, '_>,
    ) -> Result<(u32, bool), LoadError> {
        let Some(b) = elements(node).find(|c| {
            c.tag_name().name() == "bsdf"
                || (c.tag_name().name() == "ref" && c.attribute("name").is_none_or(|n| n == "bsdf"))
        }) else {
            if let Some(m) = self.default_material {
                return Ok((m, false));
            }
            let model = bsdf::material(
                x,
                node,
                &Bsdf::Smooth {
                    kd: glam::DVec3::splat(0.5),
                    gr: glam::DVec3::ZERO,
                    delta: None,
                    texture: None,
                },
            )?;
            let m = self
                .materials
                .add_delta("mitsuba:default-diffuse".into(), model);
            self.default_material = Some(m);
            return Ok((m, false));
        };
        if b.tag_name().name() == "ref" {
            let id = x.need(b, "id")?;
            return match self.named.get(&id) {
                Some((index, _)) => Ok((*index, false)),
                None => Err(x.err(b, format!("no <bsdf id=\"{id}\"> before this reference"))),
            };
        }
        let name = format!("line {}", doc::line(b));
        Ok((self.bsdf(x, dir, b, &name)?.0, true))
    }

    fn resolve(&self, dir: &Path, name: &str) -> PathBuf {
        shape::resolve(dir, &self.search, name)
    }

    /// The scene, its settings (bdpm's defaults at the film's size) and the report.
    fn finish(self, path: &Path) -> Result<LoadedScene, LoadError> {
        let ctx = Ctx { file: path };
        let sensor = self.sensor.ok_or_else(|| {
            ctx.bad(
                "sensor",
                "the scene has no <sensor type=\"perspective\">; bdpm needs a camera",
            )
        })?;
        let settings = RenderSettings {
            width: sensor.width,
            height: sensor.height,
            ..RenderSettings::default()
        };
        settings
            .validate()
            .map_err(|e| ctx.bad("sensor.film", e.to_string()))?;
        let n = self.shapes.mesh.indices.len();
        let needs = Geometry::planned_bytes(n).total() + Geometry::build_transient_bytes(n);
        self.budget
            .check(
                self.budget.textures() + self.shapes.bytes(),
                needs,
                "per-triangle data, BVH and the BVH build",
            )
            .map_err(|m| ctx.bad("shape", format!("building the scene's {n} triangles {m}")))?;
        let Shapes {
            mesh,
            texcoords,
            mut emission_texcoords,
            ..
        } = self.shapes;
        if !emission_texcoords.is_empty() {
            emission_texcoords.resize(mesh.indices.len(), [Vec2::ZERO; 3]);
        }
        let geometry = Geometry::new(mesh).map_err(|e| geometry_error(&ctx, e, 0))?;
        let report = LoadReport {
            triangles: geometry.triangle_count(),
            degenerate_triangles: geometry.degenerate_count(),
            materials: self.materials.len(),
            lights: self.lights.len(),
            gltf_files: self.files,
            import_warnings: self.warnings,
            textures: self.images.count(),
            ..LoadReport::default()
        };
        let light_count = self.lights.len();
        let mut materials = self.materials;
        let emission = EmissionTextures {
            textures: materials.take_emission_textures(),
            texcoords: emission_texcoords,
        };
        let (materials, base_colour) = materials.into_parts();
        let scene = Scene::new(geometry, materials, self.lights, sensor.camera)
            .and_then(|s| s.with_textures(SceneTextures { base_colour, texcoords }))
            .and_then(|s| s.with_emission_textures(emission))
            .map_err(|e| match e {
                bdpm_scene::SceneError::NoLight if light_count == 0 => ctx.bad("emitter", "the scene has no light: add an <emitter type=\"point\">, or an <emitter type=\"area\"> with a positive radiance inside a <shape>"),
                other => scene_error(&ctx, other, light_count),
            })?;
        Ok(LoadedScene {
            scene,
            settings,
            output: None,
            report,
        })
    }
}
