//! Spectra read back from a checkpoint as this build stores them. A checkpoint written before
//! the spectra of all-mirror boxes were packed ([`Transform::packed`]) holds them in the index
//! layout, complex values with zero imaginary parts; they are packed on the way in.

use super::transform::Transform;
use crate::engines::Saved;
use ndarray::{CowArray, Ix3};
use num_complex::Complex64;

/// The saved spectrum `name` as `t` stores it (see [`Saved::complex`]).
///
/// # Errors
/// If it is missing, real or of neither shape.
pub fn spectrum<'s>(
    saved: &'s Saved<'_>,
    name: &str,
    t: &Transform,
) -> Result<CowArray<'s, Complex64, Ix3>, String> {
    match saved.complex(name, &t.spectral_shape()) {
        Err(_) if t.packed() => {
            let index = saved.complex(name, &t.index_shape())?;
            Ok(t.packed_from(index).into())
        }
        stored => stored.map(CowArray::from),
    }
}

/// The saved single-precision spectrum `name` as `t` stores it, taken out of `saved` (see
/// [`Saved::take_single`]).
///
/// # Errors
/// If it is missing, real or of neither shape.
pub fn take_single(saved: &mut Saved<'_>, name: &str, t: &Transform) -> Result<Vec<f32>, String> {
    match saved.take_single(name, &t.spectral_shape()) {
        Err(_) if t.packed() => {
            let index = saved.take_single(name, &t.index_shape())?;
            Ok(t.packed_reals(&index))
        }
        stored => stored,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::SavedArray;
    use crate::problem::grid::AxisKind::Mirror;
    use ndarray::Array3;
    use std::borrow::Cow;

    /// A packed box's spectrum and single-precision pair saved in the index layout (as before
    /// packing) come back packed, bit for bit; saved packed, as they are; of another shape,
    /// refused. Odd and even last axes (the padding of an odd row).
    #[test]
    fn index_layout_checkpoints_are_packed_on_the_way_in() {
        for shape in [[4, 6, 7], [3, 5, 8]] {
            let mut t = Transform::new(shape, [Mirror; 3], 1);
            let mut field =
                Array3::from_shape_fn(shape, |(i, j, k)| ((i * 7 + j * 3 + k) as f64 * 0.37).sin());
            let mut packed = Array3::zeros(t.spectral_shape());
            t.forward(&mut field, &mut packed);
            let index = t.unpacked(packed.view());
            let reals = |a: &Array3<Complex64>| -> Vec<f32> {
                a.iter().flat_map(|z| [z.re as f32, z.im as f32]).collect()
            };
            for (hat, pair) in [(&index, t.index_shape()), (&packed, t.spectral_shape())] {
                let mut saved = Saved::default()
                    .array("phi_hat", SavedArray::Complex(hat.view().into()))
                    .array("s_0", SavedArray::Single(pair, Cow::Owned(reals(hat))));
                assert_eq!(spectrum(&saved, "phi_hat", &t).unwrap(), packed.view());
                let s = take_single(&mut saved, "s_0", &t).unwrap();
                assert_eq!(s, reals(&packed), "{shape:?}");
            }
            let other = Array3::zeros([shape[0], shape[1], 2]);
            let saved = Saved::default().array("phi_hat", SavedArray::Complex(other.into()));
            assert!(spectrum(&saved, "phi_hat", &t).is_err());
        }
    }
}
