//! frond's integration tests (`tests/*.rs`), one test binary: each file is a module of it,
//! named as the file, its tests `<file>::<test>` (`cargo test --test frond_tests <file>::` runs one
//! file's). One binary compiles and links the workspace's code once where a binary per file
//! did it once per file, most of the suite's build. `common` holds their shared helpers. Its
//! name has `frond` in it: `frond_output_set` plays a live frond run with this process.

mod bad_input;
mod bake_fidelity;
mod bake_rasterisers;
mod batch_cli;
mod billboard_normals;
mod chain_costs;
mod cloud_cli;
mod cloud_quality;
mod common;
mod coverage_floor;
mod eval_cli;
mod frond_output_set;
mod fuzz_import;
mod gltf_clients;
mod godot_import;
mod hostile_inputs;
mod hybrid_cloud;
mod import_warnings_cli;
mod input_limits;
mod inspect_manifest;
mod ktx2_textures;
mod lod_cli;
mod lod_error;
mod material_passthrough;
mod out_folder_gate;
mod preview_browser;
mod preview_page;
mod readme_report_table;
mod render_tree;
mod sweep_cli;
mod threejs_coverage;
mod threejs_play;
mod view_server;
