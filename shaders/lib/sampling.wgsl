// Sampling routines with their densities (solid angle unless stated).

fn sample_cos_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let phi = 2.0 * PI * u.x;
    let r = sqrt(u.y);
    return vec3<f32>(cos(phi) * r, sin(phi) * r, sqrt(max(0.0, 1.0 - u.y)));
}

fn cos_hemisphere_pdf(cos_theta: f32) -> f32 {
    return max(cos_theta, 0.0) * INV_PI;
}

// A direction around +z with density proportional to cos^n.
fn sample_power_cos(u: vec2<f32>, n: f32) -> vec3<f32> {
    let phi = 2.0 * PI * u.x;
    let cos_theta = pow(u.y, 1.0 / (n + 1.0));
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    return vec3<f32>(cos(phi) * sin_theta, sin(phi) * sin_theta, cos_theta);
}

fn power_cos_pdf(cos_theta: f32, n: f32) -> f32 {
    return (n + 1.0) * pow(max(cos_theta, 0.0), n) * (0.5 * INV_PI);
}

fn sample_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.y;
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.0 * PI * u.x;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

const UNIFORM_SPHERE_PDF: f32 = 0.0795774715459477;

// Barycentric coordinates (of v1, v2) uniform over a triangle.
fn sample_uniform_triangle(u: vec2<f32>) -> vec2<f32> {
    let s = sqrt(u.x);
    return vec2<f32>(1.0 - s, u.y * s);
}
