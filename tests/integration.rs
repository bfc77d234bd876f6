//! brume's integration tests, in one binary: each file of `tests/` is a module of it
//! (`cargo test --test integration batch::` runs one file's). One binary links once and
//! loads the library's metadata once, where 42 binaries each took a link and a crate
//! (issue 20: a fresh clone's `cargo test`). GL tests take `common::gl_lock` as before;
//! `soak.rs` stays a binary of its own, as it measures its process's memory.

mod common;

mod aerial;
mod aerial_photo;
mod batch;
mod bench_accuracy;
mod bench_speed;
mod capture;
mod cli;
mod cli_bad_input;
mod cli_scene;
mod coarse;
mod colour_profile;
mod diffuse_shader;
mod distance_fog;
mod engine_camera;
mod engine_fog;
mod external_oes;
mod fork;
mod frame_inputs;
mod fuzz_regressions;
mod gpu_errors;
mod gpu_vs_cpu;
mod host_pipeline;
mod insert;
mod io_apple;
mod io_demo;
mod io_depth;
mod io_exr_blocks;
mod io_gdepth;
mod io_image;
mod io_limits;
mod io_output;
mod layered_fog;
mod layered_table;
mod left_right;
mod limits;
mod offset_layout;
mod orientation;
mod photo_exif;
mod physical_units;
mod prep_aloe;
mod prep_edt;
mod prep_ground;
mod prep_holes;
mod prep_lidar;
mod prep_outdoor;
mod prep_street;
mod refine;
mod scene;
mod sky;
mod sun_cli;
mod sun_position;
mod timing;
mod viewer;
