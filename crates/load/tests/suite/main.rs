//! Integration tests of bdpm-load: scene files, shapes, glTF, errors and the loader fuzz harness.
//!
//! One test binary per package (the files are its modules), so CI links one executable
//! per package instead of one per file.

mod errors;
mod fuzz;
mod gltf;
mod gltf_emission;
mod gltf_materials;
mod mesh_files;
mod mitsuba;
mod mitsuba_bitmap;
mod round4;
mod scenes;
mod shapes;
