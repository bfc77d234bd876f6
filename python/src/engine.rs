//! The engine fogs in Python: `brume.Camera`, `brume.MatrixCamera`, and the requests of
//! `Renderer.distance_fog` (paper 001) and `Renderer.layered_fog` (paper 003) on a frame's
//! colour and depth buffer, through `brume::medium`, `brume::camera` and
//! `Headless::render_fog`, as `brume scene` builds them.

use super::{py_err, value_error, GlThread, ImageIn, ImageOut};
use brume::camera::{Camera, ClipDepth, FrameCamera, FrameInputs, MatrixCamera};
use brume::medium::{DensityTable, DistanceFog, FogNoise, HeightProfile, LayeredFog, Medium};
use brume::raster::{Grid, ScalarMap};
use brume::{Blur, FogBlur, GaussBlur, Precision, Scheme};
use numpy::glam_free::DMat4Rows;
use numpy::{PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;
