//! No light leaks through the Cornell box's seams (issue 12, item 1): rays leaving points within
//! 10⁻⁴ m of every edge of the box's five walls (the eight seams where two walls meet, the
//! front edges, and the diagonals that split each quad), found as the renderer finds them (as
//! hits of rays from inside the box) and spawned as it spawns them (`Scene::spawn`), all hit
//! something. The box is closed but for its front (the plane z = 0), so a ray that misses must
//! have left through the front opening: one that misses and crosses z = 0 outside the opening
//! (or never crosses it) escaped through a wall.
//!
//! Before the fix 694 of 1.9 M such rays escaped: a hit within rounding of a seam lay on the
//! neighbouring wall's plane (or just beyond it), the spawn offset moved it off its own surface
//! only, and the ray met the wall at t ≤ 0, which the triangle test rejects. Hit points are
//! now held one spawn offset inside their triangle's edges (`Hit::p`).

use bdpm_geometry::sampling::uniform_sphere;
use bdpm_geometry::{Domain, Rng};
use bdpm_suite::load;
use glam::Vec3;
use rayon::prelude::*;

/// Hit points sought per wall-triangle edge.
const POINTS_PER_EDGE: usize = 120_000;
/// Largest distance of a point from its edge, metres.
const NEAR: f32 = 1e-4;
/// Crossings of z = 0 within this distance of the opening's rim are not classified, metres.
const MARGIN: f32 = 1e-3;

/// Where a ray that found nothing left the box: `Some(true)` through a wall, `Some(false)`
/// through the front opening, `None` too near the opening's rim to tell.
fn escaped_through_a_wall(o: Vec3, d: Vec3) -> Option<bool> {
    if d.z >= 0.0 {
        // Closed for z > 0: nothing to leave through.
        return Some(true);
    }
    let p = o + d * (-o.z / d.z);
    // The opening: floor and ceiling front edges at y = 0 and y = 2.744 m, the right wall at
    // x = 0, the left wall's front edge from (2.764, 0) to (2.78, 2.744) m.
    let right = 2.764 + (2.78 - 2.764) * (p.y / 2.744);
    let inside = p.y > MARGIN && p.y < 2.744 - MARGIN && p.x > MARGIN && p.x < right - MARGIN;
    let outside = p.y < -MARGIN || p.y > 2.744 + MARGIN || p.x < -MARGIN || p.x > right + MARGIN;
    if inside {
        Some(false)
    } else if outside {
        Some(true)
    } else {
        None
    }
}

#[test]
fn rays_from_near_every_edge_of_the_box_do_not_escape() {
    let (scene, _) = load("preprint/cornell-lambert.toml", 8, 8);
    let g = scene.geometry();
    // The five walls are the scene's first five quads: floor, ceiling, back, right, left.
    let walls: Vec<u32> = (0..10).collect();
    let edges: Vec<(u32, usize)> = walls
        .iter()
        .flat_map(|&prim| (0..3).map(move |k| (prim, k)))
        .collect();
    let results: Vec<(usize, usize, Vec<String>)> = edges
        .par_iter()
        .map(|&(prim, k)| {
            let v = g.vertices(prim);
            let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
            // Height of c over the edge a–b: a point a fraction δ/h of the way to c lies δ
            // from the edge.
            let h = 2.0 * g.area(prim) / (b - a).length();
            let mut rng = Rng::new(12, Domain::Other, [prim as u64, k as u64, 0]);
            let (mut tried, mut escaped) = (0, 0);
            let mut examples = Vec::new();
            for _ in 0..POINTS_PER_EDGE {
                let s = 0.001 + 0.998 * rng.uniform();
                let on_edge = a + (b - a) * s;
                let target = on_edge + (c - on_edge) * (NEAR * rng.uniform() / h);
                // From a random point in the middle of the box, where the renderer's rays
                // come from.
                let eye = Vec3::new(
                    0.6 + 1.6 * rng.uniform(),
                    0.6 + 1.6 * rng.uniform(),
                    0.6 + 1.6 * rng.uniform(),
                );
                let dir = (target - eye).normalize();
                let Some(hit) = g.intersect(eye, dir, f32::INFINITY) else {
                    continue;
                };
                // A block in the way: not a point near this edge.
                if (hit.p - target).length() > 1e-3 {
                    continue;
                }
                let sh = scene.shade(&hit, -dir);
                let d = uniform_sphere(rng.uniform2());
                let d = if d.dot(sh.ng) < 0.0 { -d } else { d };
                let o = scene.spawn(&sh, d);
                if g.intersect(o, d, f32::INFINITY).is_some() {
                    tried += 1;
                    continue;
                }
                match escaped_through_a_wall(o, d) {
                    Some(true) => {
                        tried += 1;
                        escaped += 1;
                        if examples.len() < 3 {
                            examples.push(format!(
                                "prim {prim} edge {k}: from {o:?} (hit prim {}) along {d:?}",
                                hit.prim
                            ));
                        }
                    }
                    Some(false) => tried += 1,
                    None => {}
                }
            }
            (tried, escaped, examples)
        })
        .collect();
    let tried: usize = results.iter().map(|r| r.0).sum();
    let escaped: usize = results.iter().map(|r| r.1).sum();
    for (i, r) in results.iter().enumerate() {
        let (prim, k) = edges[i];
        eprintln!("prim {prim} edge {k}: {} rays, {} escaped", r.0, r.1);
        for e in &r.2 {
            eprintln!("  escaped: {e}");
        }
    }
    for (i, r) in results.iter().enumerate() {
        let (prim, k) = edges[i];
        assert!(
            r.0 > POINTS_PER_EDGE / 10,
            "prim {prim} edge {k}: {} rays",
            r.0
        );
    }
    eprintln!("{tried} rays from within {NEAR} m of the walls' edges, {escaped} escaped");
    assert_eq!(
        escaped, 0,
        "{escaped} of {tried} rays escaped through a wall"
    );
}
