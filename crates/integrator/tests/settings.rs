//! The renderer keeps the caller's settings: the weight clamp in force is computed and
//! reported, never written into the caller's mode, and settings errors are typed.

use bdpm_bdf::Bdf;
use bdpm_geometry::{Geometry, TriangleMesh};
use bdpm_integrator::{Mode, RenderError, RenderSettings, Renderer, Setting};
use bdpm_mis::Heuristic;
use bdpm_scene::{Camera, PointLight, Scene};
use glam::Vec3;

/// A floor lit from above, seen by an 8×8 camera.
fn scene() -> Scene {
    scene_seen_from(Vec3::ZERO)
}

/// The floor with the 8×8 camera at (0, 1, −2) m looking at `target`.
fn scene_seen_from(target: Vec3) -> Scene {
    let mut mesh = TriangleMesh::default();
    // 2 m × 2 m at y = 0, facing +y.
    mesh.push_rect(Vec3::ZERO, Vec3::Z, Vec3::X, 0);
    Scene::one_material(
        Geometry::new(mesh).unwrap(),
        Bdf::lambert(Vec3::splat(0.5)).unwrap(),
        vec![PointLight {
            position: Vec3::new(0.0, 1.0, 0.0),
            flux: Vec3::ONE,
        }],
        Camera::look_at(Vec3::new(0.0, 1.0, -2.0), target, Vec3::Y, 40.0, 8, 8).unwrap(),
    )
    .unwrap()
}

fn settings(mode: Mode) -> RenderSettings {
    RenderSettings {
        width: 8,
        height: 8,
        photons: 1000,
        mode,
        ..RenderSettings::default()
    }
}

#[test]
fn the_footprint_clamp_is_computed_not_written_into_the_mode() {
    let scene = scene();
    let s = settings(Mode::parse("optimal").unwrap());
    let r = Renderer::new(&scene, &s).unwrap();
    assert_eq!(r.settings().mode, s.mode, "the caller's mode is kept");
    assert_eq!(
        r.heuristic(),
        Some(Heuristic::Optimal {
            clamp_weights: true
        })
    );
    assert!(r.settings().weight_clamp().footprint);
    assert!(r.settings().record(r.radius(), false, None).clamp_weights);
}

/// The threshold radius has one source, the settings' `threshold_radius`: the renderer's
/// heuristic carries it, in the precision of the field.
#[test]
fn the_callers_threshold_radius_is_used() {
    let scene = scene();
    let mut s = settings(Mode::parse("threshold").unwrap());
    s.threshold_radius = 0.5;
    let r = Renderer::new(&scene, &s).unwrap();
    assert_eq!(r.heuristic(), Some(Heuristic::Threshold { radius: 0.5 }));
    s.threshold_radius = 0.3;
    let r = Renderer::new(&scene, &s).unwrap();
    assert_eq!(
        r.heuristic(),
        Some(Heuristic::Threshold {
            radius: 0.3f32.into()
        })
    );
    s.threshold_radius = -1.0;
    match Renderer::new(&scene, &s).err() {
        Some(RenderError::Settings(e)) => assert_eq!(e.setting(), Setting::ThresholdRadius),
        other => panic!("{other:?}"),
    }
}

#[test]
fn settings_errors_are_typed() {
    let scene = scene();
    let s = RenderSettings {
        spp: 0,
        ..settings(Mode::Path)
    };
    match Renderer::new(&scene, &s).err() {
        Some(RenderError::Settings(e)) => assert_eq!(e.setting(), Setting::Spp),
        other => panic!("{other:?}"),
    }
    let s = RenderSettings {
        width: 16,
        ..settings(Mode::Path)
    };
    assert!(matches!(
        Renderer::new(&scene, &s).err(),
        Some(RenderError::Resolution {
            camera: (8, 8),
            settings: (16, 8)
        })
    ));
}

#[test]
fn a_radius_in_pixels_is_resolved_against_the_camera() {
    let scene = scene();
    let footprint = scene.pixel_footprint().expect("the floor is in view");
    let mut s = settings(Mode::parse("balance").unwrap());
    s.radius_px = Some(2.5);
    let r = Renderer::new(&scene, &s).unwrap();
    assert_eq!(r.radius(), 2.5 * footprint);
    assert_eq!(r.pixel_footprint(), Some(footprint));
    // The renderer's copy holds metres only, so it validates again.
    assert_eq!(
        (r.settings().radius, r.settings().radius_px),
        (Some(2.5 * footprint), None)
    );
    assert!(r.settings().validate().is_ok());
    let rec = r.settings().record(r.radius(), true, r.pixel_footprint());
    assert!((rec.radius_px.unwrap() - 2.5).abs() < 1e-6);
    // Metres, when set, are in force over pixels (as `radius: Some(..), ..Default::default()`
    // gives over the default's half pixel).
    let metres = RenderSettings {
        radius: Some(0.03),
        ..s.clone()
    };
    assert_eq!(Renderer::new(&scene, &metres).unwrap().radius(), 0.03);

    // A camera that sees nothing has no footprint: a radius in pixels is refused by name.
    let blind = scene_seen_from(Vec3::new(0.0, 2.0, -4.0));
    assert!(matches!(
        Renderer::new(&blind, &s),
        Err(RenderError::NoFootprint(k)) if k == 2.5
    ));
}
