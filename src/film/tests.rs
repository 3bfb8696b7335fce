//! The film's fixed-point sums (exact, associative), its AOV names and its blocks, on the host.

use super::*;

#[test]
fn fixed_point_is_exact_for_float32_sums_and_associative() {
    // Every float32 from 2^-41 up is exact in the unit of 2^-64.
    for v in [0.0f32, 1.0, -2.5, 1e-3, 3.0e7, 4.6e-13, 1e16, 1e18] {
        assert_eq!(from_fixed(to_fixed(v, 0), 0), f64::from(v), "{v}");
    }
    assert_eq!(from_fixed(to_fixed(1e30, 5), 5), 1e30f32 as f64);
    let xs = [0.1f32, 1e6, 3.3e-5, 7.0, 1e-9, 2.5e12];
    let a: i128 = xs.iter().map(|&x| to_fixed(x, 0)).sum();
    let b: i128 = xs.iter().rev().map(|&x| to_fixed(x, 0)).sum();
    assert_eq!(a, b);
    assert_eq!(to_fixed(f32::NAN, 0), 0);
}

/// The conversion from the float's bits equals rounding its f64 product (half away from
/// zero, saturating), on every kind of float and both scales.
#[test]
fn to_fixed_equals_the_rounded_f64_product() {
    let reference = |v: f32, c: usize| -> i128 {
        let x = (f64::from(v) * 2f64.powi(fixed_bits(c))).round();
        if x.is_nan() { 0 } else { x as i128 }
    };
    let mut x = 0x1234_5678_9abc_def0u64;
    let mut values = vec![
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        0.5,
        1.5,
        2.5,
        -2.5,
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1e-30,
        3e-8,
        6e-8,
        1.1920929e-7,
    ];
    values.extend((0..4000).map(|_| {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        f32::from_bits((x >> 32) as u32)
    }));
    // Ties of both scales: odd multiples of 2^-25 and 2^-65.
    values.extend((0..64).map(|k| (2 * k + 1) as f32 * 2f32.powi(-25)));
    values.extend((0..64).map(|k| (2 * k + 1) as f32 * 2f32.powi(-65)));
    for v in values {
        for c in [0, crate::layout::FilmPixel::BEAUTY_SQ] {
            assert_eq!(
                to_fixed(v, c),
                reference(v, c),
                "{v:e} ({:#x}), channel {c}",
                v.to_bits()
            );
        }
    }
}

#[test]
fn aov_names_are_exr_layers_of_their_own() {
    assert!(check_aov_names(&["Direct", "IndirectDiffuse", "Reflection", "A_2"]).is_ok());
    assert!(check_aov_names::<&str>(&[]).is_ok());
    for bad in [
        &["direct"][..],
        &["Albedo"],
        &["N"],
        &["Di rect"],
        &[""],
        &["A", "A"],
    ] {
        assert!(check_aov_names(bad).is_err(), "{bad:?}");
    }
    assert_eq!(channels(0), 24);
    assert_eq!(channels(3), 36);
    assert_eq!(fixed_bits(30), 64);
    assert_eq!(fixed_bits(DEPTH_SUM), 24);
}

#[test]
fn blocks_are_counted_from_sample_zero() {
    assert_eq!(block_of(0, 1000), (0, 256));
    assert_eq!(block_of(300, 1000), (256, 512));
    assert_eq!(block_of(999, 1000), (768, 1000));
}
