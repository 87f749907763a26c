//! Error of an image against a reference, on linear radiance: the measures `compare` plots and
//! `render --reference` prints.

/// The ε of the relative MSE's denominator, (x − r)² / (r² + ε): keeps black pixels from
/// dominating (the value used by Rousselle et al. and most denoising papers).
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Error of one image against a reference, over every pixel and colour channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageError {
    /// Mean squared error.
    pub mse: f64,
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean of (x − r)² / (r² + [`REL_MSE_EPSILON`]).
    pub rel_mse: f64,
    /// Pixels of the image that are NaN or infinite (they make the errors NaN or infinite
    /// rather than being skipped).
    pub non_finite: u64,
}

/// The error of `image` against `reference` (same size, row-major RGB).
///
/// # Panics
/// When the two differ in size: callers check sizes against the files they came from.
pub fn image_error(image: &[[f32; 3]], reference: &[[f32; 3]]) -> ImageError {
    assert_eq!(image.len(), reference.len(), "image and reference differ in size");
    let (mut se, mut rel, mut non_finite) = (0.0f64, 0.0f64, 0u64);
    for (x, r) in image.iter().zip(reference) {
        if x.iter().any(|v| !v.is_finite()) {
            non_finite += 1;
        }
        for c in 0..3 {
            let d = x[c] as f64 - r[c] as f64;
            se += d * d;
            rel += d * d / (r[c] as f64 * r[c] as f64 + REL_MSE_EPSILON);
        }
    }
    let n = (image.len() * 3).max(1) as f64;
    ImageError {
        mse: se / n,
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        non_finite,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_no_error() {
        let a = vec![[0.5, 1.0, 2.0]; 4];
        let e = image_error(&a, &a);
        assert_eq!((e.mse, e.rmse, e.rel_mse, e.non_finite), (0.0, 0.0, 0.0, 0));
    }

    #[test]
    fn errors_of_a_known_difference() {
        // One channel of one pixel out of 2 x 3 values is off by 0.3 around 1.0.
        let r = vec![[1.0, 1.0, 1.0]; 2];
        let mut x = r.clone();
        x[1][2] = 1.3;
        let e = image_error(&x, &r);
        let mse = 0.09 / 6.0;
        assert!((e.mse - mse).abs() < 1e-7, "{e:?}");
        assert!((e.rmse - mse.sqrt()).abs() < 1e-7);
        assert!((e.rel_mse - mse / 1.01).abs() < 1e-7);
    }

    #[test]
    fn a_nan_pixel_is_counted_and_poisons_the_error() {
        let r = vec![[1.0; 3]; 3];
        let mut x = r.clone();
        x[0][0] = f32::NAN;
        let e = image_error(&x, &r);
        assert_eq!(e.non_finite, 1);
        assert!(e.rmse.is_nan());
    }
}
