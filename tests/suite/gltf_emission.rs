//! scenes/emissive-room.toml (issue 46, item 5): a glTF room lit only by an emissive panel
//! (emissiveFactor × KHR_materials_emissive_strength) and a sign with an emissiveTexture. Every
//! estimator must agree with `path` (independent: no merge, MIS at every vertex): the textured
//! Le enters `path` through its light samples and BDF hits, `light` through its photons and
//! light tracing, and the BDPM modes through both.

use bdpm_suite::{load, render, with_mode};

#[test]
fn gltf_emissive_room_modes_agree_with_path() {
    let (scene, mut settings) = load("emissive-room.toml", 24, 24);
    // The loader applied the sign's texture: some emitter's Le varies over its triangle.
    let textured = scene
        .emitters()
        .iter()
        .filter(|e| {
            scene
                .emission_texture(scene.geometry().material(e.prim))
                .is_some()
        })
        .count();
    assert_eq!(textured, 2, "the sign's two triangles");
    settings.radius = Some(0.01);
    let reference = render(&scene, &with_mode(&settings, "path", 256, 8, 1));
    let mut failures = Vec::new();
    for mode in ["light", "bdd0", "bdd1", "optimal-path", "balance"] {
        let film = render(&scene, &with_mode(&settings, mode, 32, 4, 50_000));
        let (within, diff, se) = bdpm_suite::films_agree(&film, &reference, 4.0);
        eprintln!("{mode:>16}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        if !(within >= 0.98 && diff.abs() < 4.0 * se && se < 0.01) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
