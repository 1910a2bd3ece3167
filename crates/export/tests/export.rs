//! The Mitsuba export of every scene in scenes/: the XML parses (read back with quick-xml)
//! with the counts of shapes, emitters and BSDFs the scene implies, the values of the
//! mapping are bdpm's (fov, film, intensity = flux/4π, IORs, conductor indices), the PLY
//! files read back through bdpm's own loader to exactly the triangles of the loaded scene,
//! textures read back to bdpm's texels, and a bad output directory is a one-line error.
//! No Mitsuba here: scripts/mitsuba-check.py renders the exports.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use bdpm_load::{LoadedScene, load_scene, load_scene_str};
use glam::{Vec2, Vec3};
use quick_xml::events::Event;
use quick_xml::{Reader, XmlVersion};

/// A parsed XML element.
#[derive(Debug, Default)]
struct Node {
    tag: String,
    attrs: Vec<(String, String)>,
    children: Vec<Node>,
}

impl Node {
    fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    fn kind(&self) -> Option<&str> {
        self.attr("type")
    }

    /// Children with this tag.
    fn all<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a Node> {
        self.children.iter().filter(move |c| c.tag == tag)
    }

    /// The `value` of the child `<tag name="name" value=".."/>`.
    fn value<'a>(&'a self, tag: &'a str, name: &str) -> Option<&'a str> {
        self.all(tag)
            .find(|c| c.attr("name") == Some(name))
            .and_then(|c| c.attr("value"))
    }

    fn float(&self, name: &str) -> f64 {
        self.value("float", name)
            .unwrap_or_else(|| panic!("no float {name} in {self:?}"))
            .parse()
            .unwrap()
    }

    fn rgb(&self, name: &str) -> Vec3 {
        let v: Vec<f32> = self
            .value("rgb", name)
            .unwrap_or_else(|| panic!("no rgb {name} in {self:?}"))
            .split(',')
            .map(|x| x.trim().parse().unwrap())
            .collect();
        Vec3::from_slice(&v)
    }
}

/// The document's root element, built with quick-xml's reader (escapes resolved).
fn parse(xml: &[u8]) -> Node {
    let mut reader = Reader::from_reader(xml);
    let mut stack = vec![Node::default()];
    let mut buf = Vec::new();
    let element = |e: &quick_xml::events::BytesStart<'_>| Node {
        tag: e.name().into_inner().to_string(),
        attrs: e
            .attributes()
            .map(|a| {
                let a = a.expect("well-formed attribute");
                let key = a.key.into_inner().to_string();
                let value = a.normalized_value(XmlVersion::Implicit1_0);
                (key, value.expect("escaped value").into_owned())
            })
            .collect(),
        children: Vec::new(),
    };
    loop {
        match reader.read_event_into(&mut buf).expect("well-formed XML") {
            Event::Start(e) => stack.push(element(&e)),
            Event::Empty(e) => stack.last_mut().unwrap().children.push(element(&e)),
            Event::End(_) => {
                let done = stack.pop().unwrap();
                stack.last_mut().expect("balanced tags").children.push(done);
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    assert_eq!(stack.len(), 1, "unclosed elements");
    let mut top = stack.pop().unwrap();
    assert_eq!(top.children.len(), 1, "one root element");
    top.children.pop().unwrap()
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every scene file of scenes/ and scenes/preprint/.
fn scene_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in ["scenes", "scenes/preprint"] {
        for entry in std::fs::read_dir(repo().join(dir)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                out.push(path);
            }
        }
    }
    out.sort();
    assert!(out.len() >= 10, "the scenes are where the test looks");
    out
}

/// The triangles bdpm's BVH holds, by material: (material, vertices, vertex normals), the
/// flat ones of a material before its smooth ones, each in mesh order; zero-area triangles
/// and exact duplicates (sorted vertex bits) left out.
type Triangle = (u32, [Vec3; 3], Option<[Vec3; 3]>);

fn rendered_triangles(loaded: &LoadedScene) -> Vec<Triangle> {
    let g = loaded.scene.geometry();
    let mut seen = HashSet::new();
    let mut out: Vec<Triangle> = (0..g.triangle_count() as u32)
        .filter(|&p| g.area(p) > 0.0)
        .filter(|&p| {
            let mut k = g.vertices(p).map(|v| v.to_array().map(f32::to_bits));
            k.sort_unstable();
            seen.insert(k)
        })
        .map(|p| (g.material(p), g.vertices(p), g.vertex_normals(p)))
        .collect();
    out.sort_by_key(|t| (t.0, t.2.is_some()));
    out
}

#[test]
fn every_scene_exports_and_its_xml_has_the_scenes_parts() {
    for path in scene_files() {
        let loaded = load_scene(&path).unwrap();
        let export = bdpm_export::mitsuba(&loaded.scene, &loaded.settings, &path).unwrap();
        let xml = &export.files.last().unwrap();
        assert_eq!(xml.path, "scene.xml");
        let root = parse(&xml.bytes);
        assert_eq!(
            (root.tag.as_str(), root.attr("version")),
            ("scene", Some("3.0.0"))
        );
        let shapes: Vec<&Node> = root.all("shape").collect();
        let bsdfs: Vec<&Node> = root.all("bsdf").collect();
        let emitters: Vec<&Node> = root.all("emitter").collect();
        let tris = rendered_triangles(&loaded);
        let materials: HashSet<u32> = tris.iter().map(|t| t.0).collect();
        let groups: HashSet<(u32, bool)> = tris.iter().map(|t| (t.0, t.2.is_some())).collect();
        let name = path.display();
        assert_eq!(emitters.len(), loaded.scene.lights().len(), "{name}");
        // Emitting materials' shapes carry an area emitter of their radiance.
        let emits = |m: u32| loaded.scene.materials()[m as usize].emits();
        let emitting_groups = groups.iter().filter(|g| emits(g.0)).count();
        let area: Vec<&Node> = shapes.iter().flat_map(|s| s.all("emitter")).collect();
        assert_eq!(area.len(), emitting_groups, "{name}");
        for e in &area {
            assert_eq!(e.kind(), Some("area"), "{name}");
            let bitmap = e
                .all("texture")
                .any(|t| t.attr("name") == Some("radiance") && t.kind() == Some("bitmap"));
            assert!(e.value("rgb", "radiance").is_some() || bitmap, "{name}");
        }
        assert_eq!(bsdfs.len(), materials.len(), "{name}");
        assert_eq!(shapes.len(), groups.len(), "{name}");
        let r = &export.report;
        assert_eq!(
            (r.shapes, r.bsdfs, r.emitters),
            (shapes.len(), bsdfs.len(), emitters.len() + area.len())
        );
        assert_eq!(r.triangles, tris.len(), "{name}");
        // Every file the XML names is part of the export, and every shape's BSDF exists.
        let files: HashSet<&str> = export.files.iter().map(|f| f.path.as_str()).collect();
        let ids: HashSet<&str> = bsdfs.iter().filter_map(|b| b.attr("id")).collect();
        for shape in &shapes {
            assert_eq!(shape.kind(), Some("ply"));
            assert!(
                files.contains(shape.value("string", "filename").unwrap()),
                "{name}"
            );
            let r = shape.all("ref").next().expect("a BSDF reference");
            assert!(ids.contains(r.attr("id").unwrap()), "{name}");
        }
        for light in &emitters {
            assert_eq!(light.kind(), Some("point"));
        }
    }
}

#[test]
fn camera_lights_and_materials_map_to_mitsubas_values() {
    let toml = r#"
        [render]
        resolution = [40, 30]
        spp = 3
        passes = 5
        [camera]
        position = [0.0, 1.0, -3.0]
        look_at = [0.0, 1.0, 0.0]
        vfov = 35
        [[light]]
        position = [0.0, 1.5, 0.0]
        flux = [12.566370614359172, 6.283185307179586, 1.0]
        [material.wall]
        kd = [0.5, 0.25, 0.125]
        [material.gold]
        type = "mirror"
        reflectance = 0.9
        eta = [0.143, 0.374, 1.442]
        k = [3.983, 2.385, 1.603]
        [material.glass]
        type = "dielectric"
        ior = 1.5
        transmit_tint = [1.0, 0.9, 0.8]
        [material.glossy]
        kd = 0.2
        gr = 0.6
        delta = 4.0
        [[shape]]
        type = "box"
        min = [-2.0, 0.0, -2.0]
        max = [2.0, 2.0, 2.0]
        facing = "inside"
        material = "wall"
        [[shape]]
        type = "quad"
        vertices = [[-1.9, 0.1, 1.9], [-1.0, 0.1, 1.9], [-1.0, 1.0, 1.9], [-1.9, 1.0, 1.9]]
        material = "gold"
        [[shape]]
        type = "sphere"
        center = [0.5, 0.5, 0.5]
        radius = 0.3
        subdivisions = 2
        material = "glass"
        [[shape]]
        type = "quad"
        vertices = [[1.0, 0.01, -1.0], [1.5, 0.01, -1.0], [1.5, 0.01, -0.5], [1.0, 0.01, -0.5]]
        material = "glossy"
    "#;
    let loaded = load_scene_str(toml, Path::new("."), Path::new("inline.toml")).unwrap();
    let export =
        bdpm_export::mitsuba(&loaded.scene, &loaded.settings, Path::new("inline.toml")).unwrap();
    let root = parse(&export.files.last().unwrap().bytes);
    let sensor = root.all("sensor").next().unwrap();
    assert_eq!(sensor.float("fov"), 35.0);
    assert_eq!(sensor.value("string", "fov_axis"), Some("y"));
    let film = sensor.all("film").next().unwrap();
    assert_eq!(film.value("integer", "width"), Some("40"));
    assert_eq!(film.value("integer", "height"), Some("30"));
    assert_eq!(film.all("rfilter").next().unwrap().kind(), Some("box"));
    let lookat = &sensor.all("transform").next().unwrap().children[0];
    assert_eq!(lookat.attr("origin"), Some("0, 1, -3"));
    // The look_at and up as the file gives them: the frame is built from the same numbers.
    assert_eq!(lookat.attr("target"), Some("0, 1, 0"));
    assert_eq!(lookat.attr("up"), Some("0, 1, 0"));
    assert_eq!(export.report.sample_count, 15);
    let light = root.all("emitter").next().unwrap();
    let intensity = light.rgb("intensity");
    let expected = Vec3::new(1.0, 0.5, 1.0 / (4.0 * std::f32::consts::PI));
    assert!(
        (intensity - expected).abs().max_element() < 1e-6,
        "{intensity}"
    );
    let bsdf = |material: &str| {
        let index = loaded
            .scene
            .materials()
            .iter()
            .position(|m| m.name == material)
            .unwrap();
        root.all("bsdf")
            .find(|b| b.attr("id") == Some(&format!("mat{index}")))
            .unwrap()
    };
    let wall = bsdf("wall");
    assert_eq!(wall.kind(), Some("twosided"));
    assert_eq!(wall.children[0].kind(), Some("diffuse"));
    assert_eq!(
        wall.children[0].rgb("reflectance"),
        Vec3::new(0.5, 0.25, 0.125)
    );
    let gold = &bsdf("gold").children[0];
    assert_eq!(gold.kind(), Some("conductor"));
    assert_eq!(gold.rgb("eta"), Vec3::new(0.143, 0.374, 1.442));
    assert_eq!(gold.rgb("k"), Vec3::new(3.983, 2.385, 1.603));
    assert_eq!(gold.rgb("specular_reflectance"), Vec3::splat(0.9));
    let glass = bsdf("glass");
    assert_eq!(
        glass.kind(),
        Some("dielectric"),
        "a dielectric is one-sided"
    );
    assert_eq!((glass.float("int_ior"), glass.float("ext_ior")), (1.5, 1.0));
    assert_eq!(
        glass.rgb("specular_transmittance"),
        Vec3::new(1.0, 0.9, 0.8)
    );
    let blend = &bsdf("glossy").children[0];
    assert_eq!(blend.kind(), Some("blendbsdf"));
    let w = blend.float("weight");
    let rough = blend.all("bsdf").nth(1).unwrap();
    let alpha = 4f64.to_radians() / 2f64.sqrt();
    assert!((rough.float("alpha") - alpha).abs() < 1e-7);
    let kd = blend.all("bsdf").next().unwrap().rgb("reflectance").x as f64 * (1.0 - w);
    let gr = rough.rgb("specular_reflectance").x as f64 * w;
    assert!(
        (kd - 0.2).abs() < 1e-6 && (gr - 0.6).abs() < 1e-6,
        "{kd} {gr}"
    );
    assert_eq!(
        export.report.warnings.len(),
        1,
        "{:?}",
        export.report.warnings
    );
    assert!(export.report.warnings[0].contains("'glossy'"));
}

/// The triangles of the export's PLY files, read by bdpm's own loader (`type = "ply"`, the
/// ply-rs-bw reader), in the XML's shape order: (material index from the BSDF id, vertices,
/// vertex normals).
fn read_back(dir: &Path, root: &Node, camera: &bdpm_scene::Camera) -> Vec<Triangle> {
    let (p, f, u) = (camera.position(), camera.forward(), camera.up());
    let mut toml = format!(
        "[camera]\nposition = [{}, {}, {}]\nlook_at = [{}, {}, {}]\nup = [{}, {}, {}]\n\
         vfov = 40\n[[light]]\nposition = [0.0, 0.0, 0.0]\nflux = 1.0\n",
        p.x,
        p.y,
        p.z,
        p.x + f.x,
        p.y + f.y,
        p.z + f.z,
        u.x,
        u.y,
        u.z
    );
    let mut materials = Vec::new();
    for shape in root.all("shape") {
        let id = shape.all("ref").next().unwrap().attr("id").unwrap();
        if !materials.contains(&id) {
            materials.push(id);
            toml += &format!("[material.{id}]\nkd = 0.5\n");
        }
        toml += &format!(
            "[[shape]]\ntype = \"ply\"\nfile = \"{}\"\nmaterial = \"{id}\"\n",
            shape.value("string", "filename").unwrap()
        );
    }
    let back = load_scene_str(&toml, dir, Path::new("read-back.toml")).unwrap();
    let g = back.scene.geometry();
    assert_eq!(g.origin(), Vec3::ZERO);
    (0..g.triangle_count() as u32)
        .map(|prim| {
            let name = &back.scene.materials()[g.material(prim) as usize].name;
            let index: u32 = name.trim_start_matches("mat").parse().unwrap();
            (index, g.vertices(prim), g.vertex_normals(prim))
        })
        .collect()
}

#[test]
fn ply_files_read_back_to_exactly_the_loaded_triangles() {
    let dir = tempfile::tempdir().unwrap();
    for path in scene_files() {
        let loaded = load_scene(&path).unwrap();
        if loaded.scene.geometry().origin() != Vec3::ZERO {
            continue;
        }
        let export = bdpm_export::mitsuba(&loaded.scene, &loaded.settings, &path).unwrap();
        let out = dir.path().join(path.file_stem().unwrap());
        bdpm_export::write(&export, &out).unwrap();
        let root = parse(&std::fs::read(out.join("scene.xml")).unwrap());
        let got = read_back(&out, &root, loaded.scene.camera());
        let want = rendered_triangles(&loaded);
        let name = path.display();
        assert_eq!(got.len(), want.len(), "{name}");
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!((g.0, g.1), (w.0, w.1), "{name}: triangle {k}");
            match (g.2, w.2) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    for (x, y) in a.iter().zip(b) {
                        // Normalised again by the loader: equal to within rounding.
                        assert!((x - y).length() < 1e-6, "{name}: triangle {k}: {x} {y}");
                    }
                }
                other => panic!("{name}: triangle {k}: normals {other:?}"),
            }
        }
    }
}

#[test]
fn textures_are_bdpms_texels_times_kd() {
    let path = repo().join("scenes/textured-box.toml");
    let loaded = load_scene(&path).unwrap();
    let export = bdpm_export::mitsuba(&loaded.scene, &loaded.settings, &path).unwrap();
    assert_eq!(export.report.textures, 1);
    let (index, texture) = (0..loaded.scene.materials().len() as u32)
        .find_map(|m| loaded.scene.texture(m).map(|t| (m, t)))
        .unwrap();
    let file = export
        .files
        .iter()
        .find(|f| f.path == format!("textures/mat{index}.exr"))
        .expect("the texture's file");
    let dir = tempfile::tempdir().unwrap();
    let exr_path = dir.path().join("t.exr");
    std::fs::write(&exr_path, &file.bytes).unwrap();
    let width = texture.size().0 as usize;
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &exr_path,
        |size, _| vec![Vec3::ZERO; size.0 * size.1],
        move |px: &mut Vec<Vec3>, p, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[p.1 * width + p.0] = Vec3::new(r, g, b);
        },
    )
    .unwrap();
    let texels = &image.layer_data.channel_data.pixels;
    let kd = loaded.scene.materials()[index as usize].bdf.kd();
    let (w, h) = texture.size();
    assert_eq!(texels.len(), (w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            assert_eq!(texels[(y * w + x) as usize], texture.texel(x, y) * kd);
        }
    }
    // The texture coordinates of its triangles are in the PLY: u, v per vertex.
    let root = parse(&export.files.last().unwrap().bytes);
    let shape = root
        .all("shape")
        .find(|s| s.all("ref").next().unwrap().attr("id") == Some(&format!("mat{index}")))
        .unwrap();
    let ply = export
        .files
        .iter()
        .find(|f| Some(f.path.as_str()) == shape.value("string", "filename"))
        .unwrap();
    let header = String::from_utf8_lossy(&ply.bytes[..300]);
    assert!(
        header.contains("property float u\nproperty float v\n"),
        "{header}"
    );
    let first = loaded
        .scene
        .texcoords(
            (0..loaded.scene.geometry().triangle_count() as u32)
                .find(|&p| loaded.scene.geometry().material(p) == index)
                .unwrap(),
        )
        .unwrap();
    assert_ne!(
        first,
        [Vec2::ZERO; 3],
        "the box has real texture coordinates"
    );
}

/// scenes/emissive-room.toml's sign: its area emitter's radiance is a bitmap of bdpm's
/// linear texels times the emission factor, read through the PLY's texture coordinates (the
/// emissive texture's: the sign has no base-colour texture).
#[test]
fn emissive_textures_are_bdpms_texels_times_the_emission_factor() {
    let path = repo().join("scenes/emissive-room.toml");
    let loaded = load_scene(&path).unwrap();
    let scene = &loaded.scene;
    let export = bdpm_export::mitsuba(scene, &loaded.settings, &path).unwrap();
    assert_eq!(export.report.textures, 1);
    let (index, texture) = (0..scene.materials().len() as u32)
        .find_map(|m| scene.emission_texture(m).map(|t| (m, t)))
        .expect("the sign's texture");
    let exr_name = format!("textures/mat{index}-emission.exr");
    let file = export.files.iter().find(|f| f.path == exr_name).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let exr_path = dir.path().join("t.exr");
    std::fs::write(&exr_path, &file.bytes).unwrap();
    let width = texture.size().0 as usize;
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &exr_path,
        |size, _| vec![Vec3::ZERO; size.0 * size.1],
        move |px: &mut Vec<Vec3>, p, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[p.1 * width + p.0] = Vec3::new(r, g, b);
        },
    )
    .unwrap();
    let texels = &image.layer_data.channel_data.pixels;
    let factor = scene.materials()[index as usize].emission;
    let (w, h) = texture.size();
    for y in 0..h {
        for x in 0..w {
            assert_eq!(texels[(y * w + x) as usize], texture.texel(x, y) * factor);
        }
    }
    let root = parse(&export.files.last().unwrap().bytes);
    let shape = root
        .all("shape")
        .find(|s| s.all("ref").next().unwrap().attr("id") == Some(&format!("mat{index}")))
        .unwrap();
    let emitter = shape.all("emitter").next().expect("an area emitter");
    let bitmap = emitter.all("texture").next().expect("a radiance texture");
    assert_eq!(
        (bitmap.attr("name"), bitmap.value("string", "filename")),
        (Some("radiance"), Some(exr_name.as_str()))
    );
    let ply = export
        .files
        .iter()
        .find(|f| Some(f.path.as_str()) == shape.value("string", "filename"))
        .unwrap();
    let header = String::from_utf8_lossy(&ply.bytes[..300]);
    assert!(
        header.contains("property float u\nproperty float v\n"),
        "{header}"
    );
}

#[test]
fn a_file_in_place_of_the_output_directory_is_a_one_line_error() {
    let path = repo().join("scenes/cornell-lambert.toml");
    let loaded = load_scene(&path).unwrap();
    let export = bdpm_export::mitsuba(&loaded.scene, &loaded.settings, &path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-dir");
    std::fs::write(&file, b"x").unwrap();
    let e = bdpm_export::write(&export, &file).unwrap_err().to_string();
    assert!(e.starts_with(&file.display().to_string()), "{e}");
    assert!(e.contains("not a directory") && !e.contains('\n'), "{e}");
    // A directory where a mesh file belongs: refused before anything is renamed.
    let out = dir.path().join("out");
    let mesh = out.join(&export.files[0].path);
    std::fs::create_dir_all(&mesh).unwrap();
    let e = bdpm_export::write(&export, &out).unwrap_err().to_string();
    assert!(e.contains("is a directory") && !e.contains('\n'), "{e}");
    assert!(!out.join("scene.xml").exists(), "nothing committed");
}
