//! BVH traversal on the GPU agrees with brute force on the CPU (in f64) for thousands of
//! random rays against random triangles and spheres: hit or miss, primitive, distance to
//! 1e-5 relative, and any-hit queries with a random distance limit; for the BVH2 and the
//! compressed wide BVH. A second scene of axis-aligned quads on a grid, with rays partly
//! parallel to the axes, exercises flat boxes and boxes sharing planes (as in Cornell boxes).
//! A third scene, on which obvhs builds trees too deep for the traversal stacks, must load
//! with trees within them, and its rays probe every scale of it.

use crate::common::{data, gpu};
use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, compile};
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::bvh::{self, BvhKind};
use lightgraph_scenes::cwbvh;
use lightgraph_scenes::gpu::primitive_kind;
use lightgraph_scenes::model::{Camera, FovAxis, Integrator, Light, Look, Material, Scene, Shape};
use std::collections::BTreeMap;

/// A small deterministic generator (xorshift64*), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn point(&mut self, r: f64) -> [f64; 3] {
        [self.range(-r, r), self.range(-r, r), self.range(-r, r)]
    }
    fn direction(&mut self) -> [f64; 3] {
        let z = 1.0 - 2.0 * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * self.next();
        [r * phi.cos(), r * phi.sin(), z]
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn f64s(a: [f32; 3]) -> [f64; 3] {
    a.map(|v| v as f64)
}

/// The CPU hit of one primitive: (t, edge margin, estimated relative error of t in f32).
/// The edge margin is how far inside the primitive the hit lies (barycentric distance to an
/// edge; squared sine of the angle to a sphere's silhouette): near 0, hit or miss is decided
/// by rounding. The error estimate follows from rounding the origin offset (|o - p| eps) and
/// the conditioning of the hit: 1/|cos| to a triangle's plane, |f| r / sqrt(disc) at a sphere.
fn cpu_intersect(o: [f64; 3], d: [f64; 3], p: &lightgraph_scenes::gpu::GpuPrimitive) -> Option<(f64, f64, f64)> {
    const EPS: f64 = f32::EPSILON as f64;
    let a = f64s(p.a);
    if p.kind == primitive_kind::SPHERE {
        let r = p.b[0] as f64;
        let f = sub(o, a);
        let b = dot(f, d);
        let c = dot(f, f) - r * r;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let fl = dot(f, f).sqrt();
        [-b - s, -b + s]
            .into_iter()
            .find(|&t| t > 0.0)
            .map(|t| (t, disc / (r * r), 2.0 * EPS * (fl * r / s.max(1e-30) + fl) / t))
    } else {
        let (e1, e2) = (f64s(p.b), f64s(p.c));
        let pv = cross(d, e2);
        let det = dot(e1, pv);
        if det == 0.0 {
            return None;
        }
        let tv = sub(o, a);
        let u = dot(tv, pv) / det;
        let qv = cross(tv, e1);
        let v = dot(d, qv) / det;
        let t = dot(e2, qv) / det;
        let n = cross(e1, e2);
        let cos = (dot(n, d) / dot(n, n).sqrt()).abs();
        let err = 2.0 * EPS * dot(tv, tv).sqrt() / (cos.max(1e-30) * t);
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some((t, u.min(v).min(1.0 - u - v), err))
    }
}

/// Random triangles and spheres, or with `axis_aligned` random axis-aligned quads with
/// corners on a grid of spacing 1/4.
fn random_scene(rng: &mut Rng, axis_aligned: bool) -> Scene {
    let mut shapes = Vec::new();
    let grid = |v: f64| ((v * 4.0).round() / 4.0) as f32;
    let (quads, triangles, spheres) = if axis_aligned { (1500, 0, 0) } else { (0, 3000, 150) };
    for _ in 0..quads {
        let mut corners = [rng.point(10.0).map(grid); 4];
        let normal = (rng.next() * 3.0) as usize;
        let (a, b) = ((normal + 1) % 3, (normal + 2) % 3);
        let (sa, sb) = (grid(rng.range(0.25, 3.0)), grid(rng.range(0.25, 3.0)));
        corners[1][a] += sa;
        corners[2][a] += sa;
        corners[2][b] += sb;
        corners[3][b] += sb;
        shapes.push(Shape::Quad {
            corners,
            material: "m".into(),
            emission: None,
        });
    }
    for _ in 0..triangles {
        let c = rng.point(10.0);
        let size = rng.range(0.2, 4.0);
        let v = [0, 1, 2].map(|_| {
            let d = rng.direction();
            [0, 1, 2].map(|k| (c[k] + size * d[k]) as f32)
        });
        shapes.push(Shape::Triangle {
            vertices: v,
            material: "m".into(),
            emission: None,
        });
    }
    for _ in 0..spheres {
        let c = rng.point(10.0).map(|v| v as f32);
        shapes.push(Shape::Sphere {
            center: c,
            radius: rng.range(0.05, 1.5) as f32,
            material: "m".into(),
        });
    }
    scene_of(shapes)
}

/// A scene of `shapes` in one diffuse material under a white background.
fn scene_of(shapes: Vec<Shape>) -> Scene {
    Scene {
        description: "test shapes".into(),
        camera: Some(Camera {
            position: [0.0; 3],
            look: Look::Forward([0.0, 0.0, 1.0]),
            up: [0.0, 1.0, 0.0],
            fov_degrees: 45.0,
            fov_axis: FovAxis::Horizontal,
            lens: None,
        }),
        gltf_camera: None,
        resolution: (1, 1),
        materials: [("m".to_string(), Material::default())].into_iter().collect(),
        shapes,
        lights: vec![Light::Background {
            radiance: [1.0; 3],
            scale: 1.0,
        }],
        integrator: Integrator::default(),
        media: Default::default(),
        camera_medium: None,
        gltf: None,
        gltf_diffuse: false,
        gltf_instances: Vec::new(),
        mitsuba: None,
        textures: Vec::new(),
    }
}

/// 500 triangles of random orientation nested around the origin, shrinking geometrically
/// from 10 to 10^-6 (the surface area heuristic peels them off one by one), and 300
/// degenerate triangles along a segment through them (boxes of zero area, which obvhs chains,
/// as in Modern Hall): unbounded, obvhs's BVH2 would be 144 levels deep, its wide BVH 141.
/// Half the rays are as in [`random_rays`], half start near a random nested triangle, at 1.5
/// to 4 times its size, and aim at a random point of it, with an any-hit limit of up to twice
/// that distance.
fn deep_scene(rng: &mut Rng, n: usize) -> (Scene, Vec<Query>) {
    let count = 500;
    let size = |k: usize| 10.0 * 1e-7f64.powf(k as f64 / (count - 1) as f64);
    // Triangle k is equilateral, in a plane size(k) / 2 from the origin, its corners size(k) / 2
    // from the plane's point nearest the origin: a ray near a smaller one seldom starts so close
    // to it that f32 cannot resolve its distance.
    let nest: Vec<[[f32; 3]; 3]> = (0..count)
        .map(|k| {
            let n = rng.direction();
            let w = rng.direction();
            let u = cross(n, w).map(|x| x / dot(cross(n, w), cross(n, w)).sqrt());
            let v = cross(n, u);
            [0.0, 1.0, 2.0].map(|i: f64| {
                let angle = 2.0 * std::f64::consts::PI * i / 3.0;
                std::array::from_fn(|j| {
                    ((0.5 * n[j] + 0.5 * (angle.cos() * u[j] + angle.sin() * v[j])) * size(k)) as f32
                })
            })
        })
        .collect();
    let mut shapes: Vec<Shape> = nest
        .iter()
        .map(|&vertices| Shape::Triangle {
            vertices,
            material: "m".into(),
            emission: None,
        })
        .collect();
    shapes.extend((0..300).map(|k| {
        let x = -1.5 + k as f32 * 0.01;
        Shape::Triangle {
            vertices: [[x, 0.0, 0.0], [x + 0.1, 0.0, 0.0], [x + 0.05, 0.0, 0.0]],
            material: "m".into(),
            emission: None,
        }
    }));
    let mut queries = random_rays(rng, n / 2, false);
    while queries.len() < n {
        let k = (rng.next() * count as f64) as usize;
        let [a, b, c] = nest[k].map(f64s);
        let (u, v) = (rng.next(), rng.next());
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        let target: [f64; 3] = std::array::from_fn(|i| a[i] + u * (b[i] - a[i]) + v * (c[i] - a[i]));
        let dir = rng.direction();
        let distance = rng.range(1.5, 4.0) * size(k);
        let o = std::array::from_fn(|i| (target[i] + distance * dir[i]) as f32);
        let to = sub(target, f64s(o));
        let d = to.map(|x| (x / dot(to, to).sqrt()) as f32);
        queries.push((o, d, rng.range(0.0, 2.0 * distance) as f32));
    }
    (scene_of(shapes), queries)
}

/// A ray query: origin, unit direction and the any-hit limit.
type Query = ([f32; 3], [f32; 3], f32);

/// `n` rays from random origins in a cube of 30 units in random directions, with any-hit
/// limits up to 30. With `axis_aligned`, half the rays have direction components of exactly
/// 0: a fifth run along an axis.
fn random_rays(rng: &mut Rng, n: usize, axis_aligned: bool) -> Vec<Query> {
    (0..n)
        .map(|_| {
            let o = rng.point(15.0).map(|v| v as f32);
            let mut d = rng.direction();
            if axis_aligned {
                let r = rng.next();
                let k = (r * 30.0) as usize % 3;
                if r < 0.3 {
                    d[k] = 0.0;
                } else if r < 0.5 {
                    d = [0.0; 3];
                    d[k] = if r < 0.4 { 1.0 } else { -1.0 };
                }
                d = d.map(|v| v / dot(d, d).sqrt());
            }
            (o, d.map(|v| v as f32), rng.range(0.0, 30.0) as f32)
        })
        .collect()
}

/// The scenes the traversal is checked on.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shapes {
    /// [`random_scene`] of triangles and spheres.
    Random,
    /// [`random_scene`] of axis-aligned quads.
    AxisAligned,
    /// [`deep_scene`].
    Deep,
}

#[test]
fn gpu_bvh2_traversal_matches_brute_force() {
    for shapes in [Shapes::Random, Shapes::AxisAligned, Shapes::Deep] {
        traversal_matches_brute_force(BvhKind::Bvh2, shapes, false);
    }
}

/// Both of the CWBVH's child loops: the loop of eight slots and the bit scan over the occupied
/// ones (`CWBVH_CHILD_SCAN`).
#[test]
fn gpu_cwbvh_traversal_matches_brute_force() {
    for shapes in [Shapes::Random, Shapes::AxisAligned, Shapes::Deep] {
        for child_scan in [false, true] {
            traversal_matches_brute_force(BvhKind::Cwbvh, shapes, child_scan);
        }
    }
}

/// Traces 4096 rays through a BVH of `kind` over `shapes` on the GPU (the CWBVH's children
/// visited by bit scan if `child_scan`) and compares with brute force; the BVH must be within
/// the traversal's stack.
fn traversal_matches_brute_force(kind: BvhKind, shapes: Shapes, child_scan: bool) {
    let mut rng = Rng(0x9E3779B97F4A7C15);
    let n = 4096usize;
    let (scene, queries) = if shapes == Shapes::Deep {
        deep_scene(&mut rng, n)
    } else {
        let axis_aligned = shapes == Shapes::AxisAligned;
        let scene = random_scene(&mut rng, axis_aligned);
        (scene, random_rays(&mut rng, n, axis_aligned))
    };
    let compiled = CompiledScene::with_bvh(&scene, kind).unwrap();
    assert_eq!(compiled.bvh_kind, kind);
    let max_depth = match kind {
        BvhKind::Bvh2 => bvh::MAX_DEPTH,
        BvhKind::Cwbvh => cwbvh::MAX_DEPTH,
    };
    assert!(
        (1..=max_depth).contains(&compiled.bvh_depth),
        "{kind:?} over {shapes:?}: {} levels",
        compiled.bvh_depth
    );
    let rays: Vec<[f32; 4]> = queries
        .iter()
        .flat_map(|&(o, d, t_any)| [[o[0], o[1], o[2], t_any], [d[0], d[1], d[2], 0.0]])
        .collect();
    let queries: Vec<([f64; 3], [f64; 3], f64)> = queries
        .iter()
        .map(|&(o, d, t_any)| (f64s(o), f64s(d), t_any as f64))
        .collect();
    let vfs = lightgraph::assets::builtin().with_front(Layer::Dir(data("")));
    let graph = Graph::load(&vfs, "graphs/bvh_query.ron").unwrap();
    let spec = Specialization {
        constants: [
            ("QUERIES".to_string(), ConstValue::U32(n as u32)),
            ("CWBVH_CHILD_SCAN".to_string(), ConstValue::Bool(child_scan)),
        ]
        .into_iter()
        .collect(),
        flags: kind
            .flag()
            .map(String::from)
            .into_iter()
            .chain(lightgraph_scenes::features::used(&compiled))
            .collect(),
    };
    let program = compile(&graph, "fused", &graph.layouts["fused"], &spec, &gpu().target()).unwrap();
    let mut externals: BTreeMap<String, Vec<u8>> = compiled
        .resources(&CompiledScene::camera(&scene, 1, 1))
        .into_iter()
        .filter(|(k, _)| graph.resource_id(k).is_some())
        .collect();
    externals.insert("rays".into(), bytemuck::cast_slice(&rays).to_vec());
    let mut instance = Instance::new(gpu(), program, &externals).unwrap();
    instance.run_frame(0, 0).unwrap();
    let results: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&instance.read("results").unwrap());

    let (mut hits, mut ambiguous, mut any_hits) = (0, 0, 0);
    let mut reasons = [0usize; 4];
    for (i, (o, d, t_any)) in queries.iter().enumerate() {
        // All CPU hits along the ray, nearest first.
        let mut cpu: Vec<(f64, f64, f64, usize)> = compiled
            .primitives
            .iter()
            .enumerate()
            .filter_map(|(j, p)| {
                cpu_intersect(*o, *d, p).map(|(t, margin, err)| (t, margin, err, compiled.order[j] as usize))
            })
            .collect();
        cpu.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Rays grazing an edge or silhouette, with two nearly equal nearest hits, or whose
        // distance f32 cannot resolve to 1e-5, may legitimately differ.
        let near_tie = cpu.len() > 1 && (cpu[1].0 - cpu[0].0) < 1e-4 * cpu[0].0;
        let grazing = cpu.first().is_some_and(|h| h.1 < 1e-4 || h.2 > 1e-5);
        let limit_tie = cpu.first().is_some_and(|h| (h.0 - t_any).abs() < 1e-4 * t_any);
        if near_tie || grazing || limit_tie {
            ambiguous += 1;
            reasons[0] += near_tie as usize;
            reasons[1] += cpu.first().is_some_and(|h| h.1 < 1e-4) as usize;
            reasons[2] += cpu.first().is_some_and(|h| h.2 > 1e-5) as usize;
            reasons[3] += limit_tie as usize;
            continue;
        }
        let r = results[i];
        match cpu.first() {
            None => assert_eq!(
                r[0], -1.0,
                "ray {i}: the GPU found a hit at t = {} where the CPU finds none",
                r[0]
            ),
            Some(&(t, _, _, prim)) => {
                hits += 1;
                assert!(r[0] > 0.0, "ray {i}: the GPU missed a hit at t = {t}");
                let gpu_prim = compiled.order[r[1].to_bits() as usize] as usize;
                assert_eq!(gpu_prim, prim, "ray {i}: closest primitive");
                assert!(
                    ((r[0] as f64) - t).abs() <= 1e-5 * t,
                    "ray {i}: t = {} on the GPU, {t} on the CPU",
                    r[0]
                );
            }
        }
        let cpu_any = cpu.first().is_some_and(|h| h.0 < *t_any);
        any_hits += cpu_any as usize;
        assert_eq!(r[2] == 1.0, cpu_any, "ray {i}: any-hit below {t_any}");
    }
    eprintln!(
        "{kind:?} (depth {}, child scan {child_scan}), {shapes:?} shapes, {n} rays: {hits} closest hits, {any_hits} any-hits, {ambiguous} skipped as ambiguous (ties {}, edges {}, f32-ill-conditioned {}, at the any-hit limit {})",
        compiled.bvh_depth, reasons[0], reasons[1], reasons[2], reasons[3]
    );
    // About 2.5% of random rays meet a surface at so grazing an angle that f32 cannot give
    // their distance to 1e-5 (the estimate above bounds the measured error; its largest
    // measured ratio was 0.83). The rest must all agree; the check needs most rays.
    assert!(
        ambiguous < n / 20,
        "{ambiguous} ambiguous rays: the test would check too little"
    );
    assert!(
        hits > n / 4 && any_hits > n / 8,
        "the rays must exercise hits ({hits}) and any-hits ({any_hits})"
    );
}
