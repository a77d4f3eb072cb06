//! Measuring shapes, independent of the engines: the φ = 0 level set ([`levelset`]) on the
//! band-limited interpolant of [`upsample`], integrals over the inside read from its facets
//! ([`facets`]), the φ = 0 surface as a triangle mesh
//! ([`surface`]), curves given by points ([`curves`]: interpolation, crossings, power-law
//! fits), the connected [`components`] of the inside, and the sharp-interface axisymmetric reference ([`axisym`]).

pub mod axisym;
pub mod components;
pub mod curves;
pub mod drop_flow;
pub mod facets;
pub mod levelset;
pub mod surface;
pub mod upsample;
