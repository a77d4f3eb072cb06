use super::dct::{dct_post_pair, dct_pre_pair, twiddle_lane};
use super::strided::{gather_in_order, scatter_in_order};
use super::*;
use ndarray::{s, Array2};

/// The DCT twiddles of a batch of lanes (two pairs at a time with AVX where the CPU has it)
/// equal the scalar formulas applied pair by pair, bit for bit, for every lane length from 0
/// to 70 (odd and even, with and without a pair left over) and padded lanes.
#[test]
fn batched_dct_twiddles_equal_the_scalar_formulas() {
    for m in 0..=70 {
        let stride = m + LANE_PAD;
        let lanes: Vec<Complex64> = (0..3 * stride)
            .map(|i| Complex64::new((i as f64 * 0.37).sin(), (i as f64 * 0.91).cos() * 3.0))
            .collect();
        let w = dct_twiddle_table(m);
        for post in [true, false] {
            let (mut batched, mut scalar) = (lanes.clone(), lanes.clone());
            if post {
                dct_twiddles::<true>(&mut batched, stride, m, &w);
            } else {
                dct_twiddles::<false>(&mut batched, stride, m, &w);
            }
            for lane in scalar.chunks_exact_mut(stride) {
                let pair = if post { dct_post_pair } else { dct_pre_pair };
                twiddle_lane(&mut lane[..m], &w, 1, pair);
            }
            let bits = |v: &[Complex64]| -> Vec<(u64, u64)> {
                v.iter().map(|z| (z.re.to_bits(), z.im.to_bits())).collect()
            };
            assert_eq!(bits(&batched), bits(&scalar), "m = {m}, post = {post}");
        }
    }
}

/// The in-order gather and scatter move each value to its place (odd and even row and column
/// counts, a block that is a column range of wider rows), and scatter undoes gather.
#[test]
fn in_order_gather_and_scatter_transpose() {
    for (rows, cols, width) in [(8, 6, 6), (7, 5, 9), (6, 3, 4), (1, 1, 1), (5, 8, 11)] {
        let value = |i: usize, j: usize| Complex64::new(i as f64, 100.0 * j as f64 + 0.5);
        let mut full = Array2::from_shape_fn((rows, width), |(i, j)| value(i, j));
        let stride = rows + LANE_PAD;
        let mut lanes = vec![Complex64::default(); stride * cols];
        gather_in_order(full.slice(s![.., ..cols]), &mut lanes, stride);
        for l in 0..cols {
            for i in 0..rows {
                assert_eq!(lanes[l * stride + i], value(i, l), "lane {l}, position {i}");
            }
        }
        lanes.iter_mut().for_each(|v| *v *= 2.0);
        scatter_in_order(&lanes, stride, full.slice_mut(s![.., ..cols]));
        for ((i, j), v) in full.indexed_iter() {
            let factor = if j < cols { 2.0 } else { 1.0 };
            assert_eq!(*v, value(i, j) * factor, "row {i}, column {j}");
        }
    }
}
