//! Forward + inverse pairs of the planned 3D real transform (`cargo bench --bench fft`).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ndarray::Array3;
use vesicle_transforms::{AxisKind, Transform};

/// Time one forward + inverse pair on a smooth-ish deterministic field.
fn bench_pair(c: &mut Criterion, name: &str, shape: [usize; 3], kinds: [AxisKind; 3]) {
    let mut group = c.benchmark_group("transform");
    if shape.iter().product::<usize>() >= 128 * 128 * 128 {
        group.sample_size(10);
    }
    let field = Array3::from_shape_fn(shape, |(i, j, k)| ((i * 7 + j * 3 + k) % 17) as f64 - 8.0);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        let mut t = Transform::new(shape, kinds, threads);
        let mut spectrum = Array3::zeros(t.spectral_shape());
        let mut x = field.clone();
        group.bench_function(BenchmarkId::new(name, format!("t{threads}")), |b| {
            pool.install(|| {
                b.iter(|| {
                    t.forward(&mut x, &mut spectrum);
                    t.inverse(&mut spectrum, &mut x);
                })
            })
        });
    }
    group.finish();
}

fn transforms(c: &mut Criterion) {
    use AxisKind::{Mirror, Periodic};
    bench_pair(c, "periodic_64", [64; 3], [Periodic; 3]);
    bench_pair(c, "periodic_128", [128; 3], [Periodic; 3]);
    bench_pair(c, "mirror_32_of_64", [32; 3], [Mirror; 3]);
    // The same size periodic: what the mirror pair would cost with real-to-complex spectra.
    bench_pair(c, "periodic_32", [32; 3], [Periodic; 3]);
}

criterion_group! {
    name = benches;
    // Plots need system fonts that build machines may lack.
    config = Criterion::default().without_plots();
    targets = transforms
}
criterion_main!(benches);
