//! The scene on the CPU: a small seeded generator, the objects, the lake, the vertex data
//! the GPU draws, and a ray cast of the same geometry (the test oracle for the depth buffer).
//!
//! Everything here is deterministic: the same seed gives the same objects, bit for bit, on
//! every machine (integer generator, no platform maths in the placement but `sin`/`cos`/
//! `powf` of the standard library, which are the same for a given build).

use crate::rng::SplitMix64;
use glam::DVec3;

/// What an object looks like.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectKind {
    /// A block: a crate near the eye, a house or a hall far away.
    Box,
    /// A tall thin box: a post near the eye, a tower far away.
    Pillar,
}

/// One box standing on the ground (y = 0), turned about its vertical axis.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneObject {
    /// Box or pillar.
    pub kind: ObjectKind,
    /// World (x, z) of the centre of its base (m).
    pub centre: [f64; 2],
    /// Half its width along its own x and z axes (m).
    pub half_width: [f64; 2],
    /// Its height above the ground (m): it spans y ∈ [0, height].
    pub height: f64,
    /// Rotation about +y (degrees): the object's own x axis is world
    /// `(cos ψ, 0, −sin ψ)` and its z axis `(sin ψ, 0, cos ψ)`.
    pub yaw_deg: f64,
    /// Linear albedo (RGB).
    pub albedo: [f32; 3],
}

impl SceneObject {
    /// The world position of a point `(lx, y, lz)` in the object's frame.
    pub fn to_world(&self, local: DVec3) -> DVec3 {
        let (s, c) = self.yaw_deg.to_radians().sin_cos();
        DVec3::new(
            self.centre[0] + c * local.x + s * local.z,
            local.y,
            self.centre[1] - s * local.x + c * local.z,
        )
    }

    /// A world direction turned into the object's frame.
    fn dir_to_local(&self, d: DVec3) -> DVec3 {
        let (s, c) = self.yaw_deg.to_radians().sin_cos();
        DVec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// The radius of the circle around its footprint (m).
    pub fn footprint_radius(&self) -> f64 {
        self.half_width[0].hypot(self.half_width[1])
    }

    /// The smallest `t > 0` at which `origin + t·dir` meets the box's surface (its
    /// entry, or its exit when `origin` is inside), by the slab method in its frame.
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let o = self.dir_to_local(origin - DVec3::new(self.centre[0], 0.0, self.centre[1]));
        let d = self.dir_to_local(dir);
        let lo = DVec3::new(-self.half_width[0], 0.0, -self.half_width[1]);
        let hi = DVec3::new(self.half_width[0], self.height, self.half_width[1]);
        let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
        for axis in 0..3 {
            let (o, d, lo, hi) = (o[axis], d[axis], lo[axis], hi[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            t_in = t_in.max(a.min(b));
            t_out = t_out.min(a.max(b));
        }
        if t_in > t_out || t_out <= 0.0 {
            return None;
        }
        Some(if t_in > 0.0 { t_in } else { t_out })
    }
}

/// A lake on the ground: an ellipse with a wavy shore. The ground shader draws water where
/// [`Lake::shore`] < 0 with the same formula (`glsl/scene/ground.frag`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lake {
    /// World (x, z) of its centre (m).
    pub centre: [f64; 2],
    /// Its radii along x and z (m), before the shore's waves.
    pub radii: [f64; 2],
}

impl Lake {
    /// Negative in the water, positive on land, in units of the radii: the normalised
    /// distance from the centre minus the shore's radius at that bearing.
    pub fn shore(&self, x: f64, z: f64) -> f64 {
        let qx = (x - self.centre[0]) / self.radii[0];
        let qz = (z - self.centre[1]) / self.radii[1];
        let a = qz.atan2(qx);
        qx.hypot(qz) - 1.0 - 0.06 * (5.0 * a + 0.7).sin() - 0.03 * (11.0 * a + 2.1).sin()
    }
}

/// What a ray met.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// The ground plane (y = 0) on land.
    Ground,
    /// The ground plane in the lake (also y = 0).
    Water,
    /// [`Scene::objects`]`[i]`.
    Object(usize),
}

/// The first surface along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The ray parameter: the point is `origin + t·dir`. With a camera's pixel ray
    /// ([`crate::camera::Camera::pixel_ray`], unit length along the view axis) it is the
    /// eye depth.
    pub t: f64,
    /// The point met.
    pub position: DVec3,
    /// What it is.
    pub surface: Surface,
}

/// The default seed of [`Scene::default`].
pub const DEFAULT_SEED: u64 = 0x6272_756D_6521;

/// How many objects [`Scene::generate`] places.
pub const OBJECT_COUNT: usize = 320;

/// The nearest and farthest object centres from the origin (m).
pub const OBJECT_DISTANCE: [f64; 2] = [3.0, 900.0];

/// Half the side of the square ground plane, centred on the origin (m): covers the far
/// plane (1000 m) of [`crate::camera::Camera::default`] in every direction, corners of the
/// view included.
pub const GROUND_HALF_SIZE: f64 = 1500.0;

/// The scene: ground, lake, objects and the sun, all in metres with y up.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The boxes and pillars.
    pub objects: Vec<SceneObject>,
    /// The lake, part of the ground plane.
    pub lake: Lake,
    /// Unit vector toward the sun.
    pub sun_direction: [f64; 3],
    /// Half the side of the square ground plane (m).
    pub ground_half_size: f64,
}

impl Default for Scene {
    /// [`Scene::generate`] with [`DEFAULT_SEED`].
    fn default() -> Self {
        Scene::generate(DEFAULT_SEED)
    }
}

/// Linear albedos of the objects: plaster, brick, ochre, slate, concrete, dark wood, teal,
/// yellow paint, terracotta, pale stone.
const PALETTE: [[f64; 3]; 10] = [
    [0.55, 0.52, 0.47],
    [0.30, 0.08, 0.05],
    [0.45, 0.30, 0.10],
    [0.10, 0.15, 0.25],
    [0.30, 0.30, 0.29],
    [0.12, 0.07, 0.04],
    [0.05, 0.25, 0.22],
    [0.60, 0.45, 0.06],
    [0.42, 0.16, 0.08],
    [0.62, 0.60, 0.55],
];

impl Scene {
    /// The sun's azimuth (degrees, 0 along −z, 90 along +x, as a camera's yaw) and
    /// elevation: behind the default camera, to its right.
    pub const SUN_AZIMUTH_DEG: f64 = 120.0;
    /// The sun's elevation above the horizon (degrees).
    pub const SUN_ELEVATION_DEG: f64 = 35.0;

    /// Places [`OBJECT_COUNT`] objects from `seed`: centres at 3 to 900 m from the origin
    /// (denser near, `r = 3 + 897·u^1.6`), three in four within ±55° of −z (the default
    /// view) and the rest all around; sizes grow with distance (`max((r/25)^0.7, 0.35)`) so
    /// that far ones stay visible; none in the lake, none nearer than 2.5 m to the origin, and none
    /// higher than `1.7 + 0.4·(nearest distance)`, so that from the default eye nothing
    /// rises more than 21.8° above the horizon (the top of a level default view is sky).
    pub fn generate(seed: u64) -> Scene {
        let mut rng = SplitMix64::new(seed);
        let lake = Lake {
            centre: [-20.0, -95.0],
            radii: [55.0, 70.0],
        };
        let [r_min, r_max] = OBJECT_DISTANCE;
        let mut objects = Vec::with_capacity(OBJECT_COUNT);
        let mut attempts = 0;
        while objects.len() < OBJECT_COUNT && attempts < 100 * OBJECT_COUNT {
            attempts += 1;
            let r = r_min + (r_max - r_min) * rng.unit().powf(1.6);
            let azimuth = if rng.unit() < 0.75 {
                rng.range(-55.0, 55.0)
            } else {
                rng.range(0.0, 360.0)
            }
            .to_radians();
            let (x, z) = (r * azimuth.sin(), -r * azimuth.cos());
            let scale = (r / 25.0).powf(0.7).max(0.35);
            let kind = if rng.unit() < 0.3 {
                ObjectKind::Pillar
            } else {
                ObjectKind::Box
            };
            let (half_width, height) = match kind {
                ObjectKind::Pillar => {
                    let w = scale * rng.range(0.15, 0.5);
                    ([w, w * rng.range(0.8, 1.25)], scale * rng.range(3.0, 8.0))
                }
                ObjectKind::Box => (
                    [scale * rng.range(0.3, 1.0), scale * rng.range(0.3, 1.0)],
                    scale * rng.range(0.4, 2.5),
                ),
            };
            let yaw_deg = rng.range(0.0, 90.0);
            let colour = PALETTE[rng.below(PALETTE.len())];
            let shade = rng.range(0.8, 1.2);
            let footprint = half_width[0].hypot(half_width[1]);
            let nearest = r - footprint;
            if nearest < 2.5 {
                continue;
            }
            let lake_margin = footprint / lake.radii[0].min(lake.radii[1]) + 0.08;
            if lake.shore(x, z) < lake_margin {
                continue;
            }
            objects.push(SceneObject {
                kind,
                centre: [x, z],
                half_width,
                height: height.min(1.7 + 0.4 * nearest),
                yaw_deg,
                albedo: colour.map(|c| (c * shade).min(1.0) as f32),
            });
        }
        // Nearest first: the GPU draws them in this order, and the depth test then skips
        // most hidden fragments of the farther ones.
        objects.sort_by(|a, b| {
            let d = |o: &SceneObject| o.centre[0].hypot(o.centre[1]);
            d(a).total_cmp(&d(b))
        });
        let (az, el) = (
            Self::SUN_AZIMUTH_DEG.to_radians(),
            Self::SUN_ELEVATION_DEG.to_radians(),
        );
        Scene {
            objects,
            lake,
            sun_direction: [az.sin() * el.cos(), el.sin(), -az.cos() * el.cos()],
            ground_half_size: GROUND_HALF_SIZE,
        }
    }

    /// The first surface along `origin + t·dir`, t > 0 (`dir` need not be unit), as the
    /// GPU draws it but without a far plane: the caller compares `t` with its own.
    pub fn ray_cast(&self, origin: DVec3, dir: DVec3) -> Option<Hit> {
        let mut best: Option<(f64, Surface)> = None;
        if dir.y != 0.0 {
            let t = -origin.y / dir.y;
            let p = origin + dir * t;
            let half = self.ground_half_size;
            if t > 0.0 && p.x.abs() <= half && p.z.abs() <= half {
                let surface = if self.lake.shore(p.x, p.z) < 0.0 {
                    Surface::Water
                } else {
                    Surface::Ground
                };
                best = Some((t, surface));
            }
        }
        for (i, object) in self.objects.iter().enumerate() {
            if let Some(t) = object.intersect(origin, dir) {
                if best.is_none_or(|(b, _)| t < b) {
                    best = Some((t, Surface::Object(i)));
                }
            }
        }
        best.map(|(t, surface)| Hit {
            t,
            position: origin + dir * t,
            surface,
        })
    }
}

/// Floats per vertex: position (3), normal (3), colour (4: linear albedo and a contact
/// shadow factor in alpha).
pub(crate) const VERTEX_FLOATS: usize = 10;

/// The vertex and index data of the scene: the objects' triangles first, then the
/// ground's.
pub(crate) struct MeshData {
    pub vertices: Vec<f32>,
    pub indices: Vec<u32>,
    /// Index count of the objects (indices `0..objects`).
    pub objects: usize,
    /// Index count of the ground (indices `objects..objects + ground`).
    pub ground: usize,
}

/// Ground grid lines from the origin outward (m): fine near the eye, so that no triangle
/// the eye stands on is huge on screen, coarse far away.
const GROUND_LINES: [f64; 20] = [
    1.5, 3.0, 5.0, 8.0, 12.0, 18.0, 25.0, 35.0, 50.0, 70.0, 100.0, 150.0, 200.0, 300.0, 400.0,
    600.0, 800.0, 1000.0, 1250.0, 1500.0,
];

/// Contact shadow at the foot of an object's walls (alpha of the vertex colour).
const FOOT_SHADE: f32 = 0.55;

impl MeshData {
    pub fn new(scene: &Scene) -> Self {
        let mut mesh = MeshData {
            vertices: Vec::new(),
            indices: Vec::new(),
            objects: 0,
            ground: 0,
        };
        for object in &scene.objects {
            mesh.push_box(object);
        }
        mesh.objects = mesh.indices.len();
        mesh.push_ground(scene.ground_half_size);
        mesh.ground = mesh.indices.len() - mesh.objects;
        mesh
    }

    fn push_vertex(&mut self, p: DVec3, n: DVec3, colour: [f32; 4]) -> u32 {
        let index = (self.vertices.len() / VERTEX_FLOATS) as u32;
        self.vertices
            .extend([p.x, p.y, p.z, n.x, n.y, n.z].map(|v| v as f32));
        self.vertices.extend(colour);
        index
    }

    /// A quad `a b c d` (in order around it), wound counter-clockwise seen from its
    /// normal's side.
    fn push_quad(&mut self, corners: [DVec3; 4], normal: DVec3, colours: [[f32; 4]; 4]) {
        let [a, b, c, _] = corners;
        let ccw = (b - a).cross(c - a).dot(normal) > 0.0;
        let v: Vec<u32> = corners
            .iter()
            .zip(colours)
            .map(|(&p, colour)| self.push_vertex(p, normal, colour))
            .collect();
        let order = if ccw {
            [0, 1, 2, 0, 2, 3]
        } else {
            [0, 2, 1, 0, 3, 2]
        };
        self.indices.extend(order.map(|i| v[i]));
    }

    fn push_box(&mut self, o: &SceneObject) {
        let [hx, hz] = o.half_width;
        let h = o.height;
        let [r, g, b] = o.albedo;
        let (lit, foot) = ([r, g, b, 1.0], [r, g, b, FOOT_SHADE]);
        let corner = |x: f64, y: f64, z: f64| o.to_world(DVec3::new(x * hx, y * h, z * hz));
        let normal = |n: DVec3| o.to_world(n) - o.to_world(DVec3::ZERO);
        // Four walls: bottom corners shaded, top corners lit.
        for (n, u) in [
            (DVec3::X, DVec3::Z),
            (DVec3::NEG_X, DVec3::NEG_Z),
            (DVec3::Z, DVec3::NEG_X),
            (DVec3::NEG_Z, DVec3::X),
        ] {
            let p = |s: f64, y: f64| corner(n.x + s * u.x, y, n.z + s * u.z);
            self.push_quad(
                [p(-1.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(-1.0, 1.0)],
                normal(n),
                [foot, foot, lit, lit],
            );
        }
        let top = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        self.push_quad(top.map(|(x, z)| corner(x, 1.0, z)), DVec3::Y, [lit; 4]);
        self.push_quad(top.map(|(x, z)| corner(x, 0.0, z)), DVec3::NEG_Y, [foot; 4]);
    }

    fn push_ground(&mut self, half: f64) {
        let mut lines: Vec<f64> = GROUND_LINES
            .iter()
            .copied()
            .filter(|&v| v < half)
            .chain([half])
            .collect();
        lines = lines
            .iter()
            .rev()
            .map(|v| -v)
            .chain([0.0])
            .chain(lines.iter().copied())
            .collect();
        let white = [1.0; 4];
        for z in lines.windows(2) {
            for x in lines.windows(2) {
                let p = |x: f64, z: f64| DVec3::new(x, 0.0, z);
                self.push_quad(
                    [p(x[0], z[0]), p(x[0], z[1]), p(x[1], z[1]), p(x[1], z[0])],
                    DVec3::Y,
                    [white; 4],
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_is_deterministic_and_spread_in_depth() {
        let scene = Scene::default();
        assert_eq!(scene, Scene::generate(DEFAULT_SEED));
        assert_ne!(scene.objects, Scene::generate(7).objects);
        assert_eq!(scene.objects.len(), OBJECT_COUNT);
        let distances: Vec<f64> = scene
            .objects
            .iter()
            .map(|o| o.centre[0].hypot(o.centre[1]))
            .collect();
        assert!(
            distances.windows(2).all(|w| w[0] <= w[1]),
            "sorted near first"
        );
        assert!(distances[0] < 6.0, "nearest {}", distances[0]);
        assert!(distances[OBJECT_COUNT - 1] > 800.0);
        for band in [[3.0, 10.0], [10.0, 50.0], [50.0, 200.0], [200.0, 900.0]] {
            let n = distances
                .iter()
                .filter(|&&d| d >= band[0] && d < band[1])
                .count();
            assert!(n >= 10, "only {n} objects in {band:?} m");
        }
        for o in &scene.objects {
            let nearest = o.centre[0].hypot(o.centre[1]) - o.footprint_radius();
            assert!(nearest >= 2.5);
            assert!(o.height <= 1.7 + 0.4 * nearest + 1e-9);
            assert!(scene.lake.shore(o.centre[0], o.centre[1]) > 0.0);
        }
        let sun = DVec3::from_array(scene.sun_direction);
        assert!((sun.length() - 1.0).abs() < 1e-12 && sun.y > 0.5);
    }

    #[test]
    fn rays_meet_boxes_where_their_faces_are() {
        let o = SceneObject {
            kind: ObjectKind::Box,
            centre: [0.0, -10.0],
            half_width: [1.0, 2.0],
            height: 3.0,
            yaw_deg: 90.0,
            albedo: [0.5; 3],
        };
        // Turned by 90°, its local z (half-width 2) lies along world x: the near face is
        // at z = −9, 2 m wide each side of the axis, the eye 9 m away.
        let eye = DVec3::new(0.0, 1.0, 0.0);
        let t = o.intersect(eye, DVec3::NEG_Z).unwrap();
        assert!((t - 9.0).abs() < 1e-12, "{t}");
        let slanted = |s: f64| DVec3::new(s, 0.0, -1.0);
        assert!((o.intersect(eye, slanted(0.21)).unwrap() - 9.0).abs() < 1e-12);
        assert!(o.intersect(eye, slanted(0.23)).is_none());
        let unturned = SceneObject {
            yaw_deg: 0.0,
            ..o.clone()
        };
        assert!(unturned.intersect(eye, slanted(0.21)).is_none());
        assert!(o.intersect(eye, DVec3::Z).is_none());
        assert!(o
            .intersect(DVec3::new(0.0, 3.5, 0.0), DVec3::NEG_Z)
            .is_none());
        let inside = DVec3::new(0.0, 1.0, -10.0);
        assert!((o.intersect(inside, DVec3::NEG_Z).unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_ground_ray_cast_finds_the_lake_and_the_land() {
        let scene = Scene::default();
        let eye = DVec3::new(0.0, 1.7, 0.0);
        let to = |x: f64, z: f64| DVec3::new(x, 0.0, z) - eye;
        let lake = scene.ray_cast(eye, to(-20.0, -95.0)).unwrap();
        assert_eq!(lake.surface, Surface::Water);
        assert!(lake.position.y.abs() < 1e-12);
        assert!(scene.ray_cast(eye, DVec3::Y).is_none());
    }

    #[test]
    fn the_mesh_holds_every_box_and_the_ground() {
        let scene = Scene::default();
        let mesh = MeshData::new(&scene);
        assert_eq!(mesh.objects, 36 * scene.objects.len());
        assert_eq!(mesh.ground, 6 * 40 * 40);
        assert_eq!(mesh.indices.len(), mesh.objects + mesh.ground);
        let vertices = mesh.vertices.len() / VERTEX_FLOATS;
        assert!(mesh.indices.iter().all(|&i| (i as usize) < vertices));
        // Every triangle is counter-clockwise seen from its normal's side.
        let at = |i: u32| {
            let v = &mesh.vertices[i as usize * VERTEX_FLOATS..];
            (
                DVec3::new(v[0].into(), v[1].into(), v[2].into()),
                DVec3::new(v[3].into(), v[4].into(), v[5].into()),
            )
        };
        for tri in mesh.indices.chunks(3) {
            let ((a, n), (b, _), (c, _)) = (at(tri[0]), at(tri[1]), at(tri[2]));
            assert!((b - a).cross(c - a).dot(n) > 0.0);
        }
    }
}
