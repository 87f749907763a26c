#if MEDIA_GRID
// Heterogeneous media (MEDIA_GRID; docs/media.md): a medium whose `kind` k > 0 has the density
// grid k - 1 of `media_grids`, its coefficients per unit density and its extinction grey.
// Free flights are sampled by delta tracking and shadow rays' transmittance estimated by ratio
// tracking, both against a coarse grid of majorants (the largest density each cell can see)
// walked cell by cell (DDA) over the part of the ray inside the grid's box; outside the box
// the density is zero.

// The most tentative collisions one tracking takes; a free flight that would take more ends the
// path, a transmittance estimate is zero (docs/media.md).
const GRID_MAX_STEPS: u32 = 4096u;
// More than the cells a ray crosses in a majorant grid (at most 16 an axis).
const MAJORANT_WALK_CELLS: u32 = 64u;

// A density grid as `media_grids` holds it (six vec4s: GpuDensityGrid in scenes/src/gpu.rs).
struct DensityGrid {
    to_grid_x: vec4<f32>,   // rows of the affine map from the world to the unit cube
    to_grid_y: vec4<f32>,
    to_grid_z: vec4<f32>,
    res: vec3<u32>,         // voxels along x, y, z
    offset: u32,            // its first density in `media_density`
    cells: vec3<u32>,       // cells of its majorant grid along x, y, z
    majorant_offset: u32,   // its first majorant in `media_density`
    nearest: bool,          // nearest voxel instead of trilinear interpolation
}

fn density_grid_at(g: u32) -> DensityGrid {
    let base = 6u * g;
    let r = bitcast<vec4<u32>>(media_grids[base + 3u]);
    let c = bitcast<vec4<u32>>(media_grids[base + 4u]);
    let f = bitcast<vec4<u32>>(media_grids[base + 5u]);
    return DensityGrid(
        media_grids[base], media_grids[base + 1u], media_grids[base + 2u],
        r.xyz, r.w, c.xyz, c.w, f.x != 0u,
    );
}

// Whether medium `m` (not vacuum) has a density grid.
fn medium_has_grid(medium: Medium) -> bool {
    return medium.kind != 0u;
}

// A point of the world in the grid's unit cube.
fn grid_point(grid: DensityGrid, p: vec3<f32>) -> vec3<f32> {
    let q = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(grid.to_grid_x, q), dot(grid.to_grid_y, q), dot(grid.to_grid_z, q));
}

// The density of voxel `i` (clamped to the grid, as Mitsuba's `clamp` wrap mode).
fn grid_voxel(grid: DensityGrid, i: vec3<i32>) -> f32 {
    let c = vec3<u32>(clamp(i, vec3<i32>(0), vec3<i32>(grid.res) - 1));
    return media_density[grid.offset + (c.z * grid.res.y + c.y) * grid.res.x + c.x];
}

// The density at `u`, a point of the unit cube: voxel centres at (i + 0.5) / res.
fn grid_density(grid: DensityGrid, u: vec3<f32>) -> f32 {
    let x = u * vec3<f32>(grid.res);
    if (grid.nearest) {
        return grid_voxel(grid, vec3<i32>(floor(x)));
    }
    let s = x - 0.5;
    let i = vec3<i32>(floor(s));
    let f = s - floor(s);
    let c00 = mix(grid_voxel(grid, i), grid_voxel(grid, i + vec3<i32>(1, 0, 0)), f.x);
    let c10 = mix(grid_voxel(grid, i + vec3<i32>(0, 1, 0)), grid_voxel(grid, i + vec3<i32>(1, 1, 0)), f.x);
    let c01 = mix(grid_voxel(grid, i + vec3<i32>(0, 0, 1)), grid_voxel(grid, i + vec3<i32>(1, 0, 1)), f.x);
    let c11 = mix(grid_voxel(grid, i + vec3<i32>(0, 1, 1)), grid_voxel(grid, i + vec3<i32>(1, 1, 1)), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// A ray from `origin` along `d` in the grid's unit cube: its origin there, its direction (t
// measures the same distances as in the world), and the part [t.x, t.y] of [0, t_end] inside
// the cube (empty: t.x >= t.y).
struct GridRay {
    o: vec3<f32>,
    d: vec3<f32>,
    t: vec2<f32>,
}

fn grid_ray(grid: DensityGrid, origin: vec3<f32>, d: vec3<f32>, t_end: f32) -> GridRay {
    let o = grid_point(grid, origin);
    let v = vec3<f32>(dot(grid.to_grid_x.xyz, d), dot(grid.to_grid_y.xyz, d), dot(grid.to_grid_z.xyz, d));
    let safe = select(v, vec3<f32>(1e-30), abs(v) < vec3<f32>(1e-30));
    let a = -o / safe;
    let b = (1.0 - o) / safe;
    let near = max(max_component(min(a, b)), 0.0);
    let far = min(min(min(max(a.x, b.x), max(a.y, b.y)), max(a.z, b.z)), t_end);
    return GridRay(o, safe, vec2<f32>(near, far));
}

// A walk along a grid ray through the cells of the majorant grid (Amanatides and Woo's DDA):
// the cell at `t`, and where the ray leaves it along each axis.
struct MajorantWalk {
    cell: vec3<i32>,
    step: vec3<i32>,
    t_next: vec3<f32>,
    t_delta: vec3<f32>,
    t: f32,
    t_end: f32,
}

fn majorant_walk(grid: DensityGrid, ray: GridRay) -> MajorantWalk {
    let n = vec3<f32>(grid.cells);
    let cell = clamp(vec3<i32>(floor((ray.o + ray.t.x * ray.d) * n)), vec3<i32>(0), vec3<i32>(grid.cells) - 1);
    let up = ray.d > vec3<f32>(0.0);
    let bound = (vec3<f32>(cell) + select(vec3<f32>(0.0), vec3<f32>(1.0), up)) / n;
    return MajorantWalk(
        cell, select(vec3<i32>(-1), vec3<i32>(1), up), (bound - ray.o) / ray.d, abs(1.0 / (ray.d * n)),
        ray.t.x, ray.t.y,
    );
}

// The majorant density of the walk's cell.
fn majorant_at(grid: DensityGrid, cell: vec3<i32>) -> f32 {
    let c = vec3<u32>(clamp(cell, vec3<i32>(0), vec3<i32>(grid.cells) - 1));
    return media_density[grid.majorant_offset + (c.z * grid.cells.y + c.y) * grid.cells.x + c.x];
}

// Moves the walk to the next tentative collision, `tau` further in optical depth of the
// majorant (extinction `sigma_t` per unit density times each cell's majorant density): returns
// the majorant density there, or 0 where the walk reaches its end first.
fn majorant_walk_to(grid: DensityGrid, sigma_t: f32, walk: ptr<function, MajorantWalk>, tau: f32) -> f32 {
    var left = tau;
    for (var i = 0u; i < MAJORANT_WALK_CELLS; i++) {
        let tn = (*walk).t_next;
        let end = min(min(min(tn.x, tn.y), tn.z), (*walk).t_end);
        let bound = majorant_at(grid, (*walk).cell);
        let depth = sigma_t * bound * max(end - (*walk).t, 0.0);
        if (depth > left) {
            (*walk).t += left / (sigma_t * bound);
            return bound;
        }
        left -= depth;
        (*walk).t = end;
        if (end >= (*walk).t_end) {
            return 0.0;
        }
        var axis = vec3<bool>(false, false, true);
        if (tn.x <= tn.y && tn.x <= tn.z) {
            axis = vec3<bool>(true, false, false);
        } else if (tn.y <= tn.z) {
            axis = vec3<bool>(false, true, false);
        }
        (*walk).cell += select(vec3<i32>(0), (*walk).step, axis);
        (*walk).t_next += select(vec3<f32>(0.0), (*walk).t_delta, axis);
    }
    (*walk).t = (*walk).t_end;
    return 0.0;
}

// A free flight by delta tracking through grid medium `medium` towards a surface at
// `t_surface`: tentative collisions at the rate of the majorant grid, each real with the
// probability density / majorant. The first distance uses `u`, later numbers come from `rng`.
// The weight is the albedo where the path scatters (grey extinction), 1 where it reaches the
// surface.
fn grid_free_flight(medium: Medium, origin: vec3<f32>, d: vec3<f32>, t_surface: f32, u: f32, rng: ptr<function, u32>) -> FreeFlight {
    let grid = density_grid_at(medium.kind - 1u);
    let ray = grid_ray(grid, origin, d, t_surface);
    let passed = FreeFlight(t_surface, false, vec3<f32>(1.0));
    if (ray.t.x >= ray.t.y || medium.sigma_t.x <= 0.0) {
        return passed;
    }
    var walk = majorant_walk(grid, ray);
    var v = u;
    for (var i = 0u; i < GRID_MAX_STEPS; i++) {
        let bound = majorant_walk_to(grid, medium.sigma_t.x, &walk, -log(max(1.0 - v, 1e-30)));
        if (bound <= 0.0) {
            return passed;
        }
        if (rng_f32(rng) * bound < grid_density(grid, ray.o + walk.t * ray.d)) {
            return FreeFlight(walk.t, true, medium.sigma_s / medium.sigma_t.x);
        }
        v = rng_f32(rng);
    }
    return FreeFlight(t_surface, false, vec3<f32>(0.0));
}

// The transmittance of grid medium `medium` from `origin` along `d` for `t_end`, estimated by
// ratio tracking: the product of 1 - density / majorant over tentative collisions at the rate
// of the majorant grid, drawn from `rng`.
fn grid_transmittance(medium: Medium, origin: vec3<f32>, d: vec3<f32>, t_end: f32, rng: ptr<function, u32>) -> f32 {
    let grid = density_grid_at(medium.kind - 1u);
    let ray = grid_ray(grid, origin, d, t_end);
    if (ray.t.x >= ray.t.y || medium.sigma_t.x <= 0.0) {
        return 1.0;
    }
    var walk = majorant_walk(grid, ray);
    var tr = 1.0;
    for (var i = 0u; i < GRID_MAX_STEPS; i++) {
        let bound = majorant_walk_to(grid, medium.sigma_t.x, &walk, -log(max(1.0 - grid_rng_f32(rng), 1e-30)));
        if (bound <= 0.0) {
            return tr;
        }
        tr *= max(1.0 - grid_density(grid, ray.o + walk.t * ray.d) / bound, 0.0);
        if (tr <= 0.0) {
            return 0.0;
        }
    }
    return 0.0;
}

// A stream of random numbers for a shadow ray's ratio tracking, which has none of its path:
// seeded by hashing the ray (its origin, direction and length), so it is drawn afresh for
// every shadow ray and alike in every layout.
fn grid_shadow_rng(origin: vec3<f32>, d: vec3<f32>, distance: f32) -> u32 {
    let o = bitcast<vec3<u32>>(origin);
    let v = bitcast<vec3<u32>>(d);
    var h = rng_hash(o.x ^ rng_hash(o.y ^ rng_hash(o.z)));
    h = rng_hash(h ^ v.x ^ rng_hash(v.y ^ rng_hash(v.z ^ bitcast<u32>(distance))));
    return h;
}

// Uniform in [0, 1) from the PCG stream `*state` (not the path's hooked source).
fn grid_rng_f32(state: ptr<function, u32>) -> f32 {
    return f32(rng_pcg_u32(state) >> 8u) * (1.0 / 16777216.0);
}

// A free flight through medium `m`: delta tracking in a grid medium, else as
// `medium_free_flight` (which draws only `u`).
fn media_free_flight(m: i32, origin: vec3<f32>, d: vec3<f32>, t_surface: f32, u: f32, rng: ptr<function, u32>) -> FreeFlight {
    if (m != VACUUM && medium_has_grid(medium_at(m))) {
        return grid_free_flight(medium_at(m), origin, d, t_surface, u, rng);
    }
    return medium_free_flight(m, t_surface, u);
}

// The transmittance of medium `m` from `origin` along `d` for `t`: ratio tracking in a grid
// medium (drawing from `rng`), else exact.
fn media_transmittance(m: i32, origin: vec3<f32>, d: vec3<f32>, t: f32, rng: ptr<function, u32>) -> vec3<f32> {
    if (m != VACUUM && medium_has_grid(medium_at(m))) {
        return vec3<f32>(grid_transmittance(medium_at(m), origin, d, t, rng));
    }
    return medium_transmittance(m, t);
}
#endif
