//! Workspace integration tests of bdpm: statistical render tests against exact answers and
//! independent references, determinism, stages, stiff inputs, geometry robustness.
//!
//! One test binary per package (the files are its modules), so CI links one executable
//! per package instead of one per file.

mod area_lights;
mod cache;
mod cornell;
mod determinism;
mod doc_claims;
mod furnace;
mod gltf_emission;
mod gltf_glass;
mod light_leak;
mod mesh_files;
mod mitsuba_import;
mod mitsuba_round_trip;
mod new_scenes;
mod noise_model;
mod precision;
mod predict;
mod predict_area;
mod predict_specular;
mod seams;
mod smooth_spheres;
mod specular;
mod specular_scenes;
mod stages;
mod stiff;
mod textures;
mod weight_inputs;
mod weight_map;
