// Items of ambient occlusion.

struct AoSample {
    pixel: u32,
}

struct OcclusionRay {
    origin: vec3<f32>,
    pixel: u32,
    direction: vec3<f32>,
}
