//! The build stage: what the GPU's algorithms need built on the host from the resolved scene:
//! shapes flattened into primitives and lights, the BVH (binary or compressed wide), the
//! light-selection alias table and the lights' powers, rough plastics' coating tables.

pub mod acceleration;
pub mod alias;
pub mod bvh;
pub mod cwbvh;
pub mod flatten;
pub mod light_power;
pub mod plastic;
