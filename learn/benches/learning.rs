//! Learning speed: the online detector per frame, OKL against demonstration length, OKL
//! against the mACL baseline on the same demonstrations (thesis §4.6.8), and the TV denoiser
//! on OKL's fitting-error signals against its worst case.
//!
//! Run with `cargo bench -p akl-learn --bench learning`; results are in BENCHMARKS.md.
// `criterion_group!` generates a public function without documentation.
#![allow(missing_docs)]

use akl_learn::calibration::Calibration;
use akl_learn::okl::runs;
use akl_learn::okl::synth::DemoBuilder;
use akl_learn::okl::{fit_line, fitting_errors};
use akl_learn::{learn_spec, Answer, Demo, Detector, LearnOptions, Method};

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::time::Duration;

/// A pick-and-carry cycle repeated until the demo lasts `seconds` at 100 Hz: reach (curved),
/// grasp, carry in a required line, release, return. One cycle is about 9 s.
fn demo(seconds: f64) -> Demo {
    let mut b = DemoBuilder::new("bench", [0.3, 0.0, 0.4], 100.0, 0.0005, 7)
        .object("part", [0.45, 0.3, 0.2]);
    let mut cycles = 0;
    while (cycles as f64) * 9.0 < seconds {
        b = b
            .curve([0.45, 0.3, 0.25], 0.25)
            .pause(0.3)
            .grasp("part")
            .curve([0.55, 0.2, 0.3], 0.25)
            .line([0.55, -0.2, 0.3], 0.15, Some(Answer::Yes))
            .curve([0.45, -0.3, 0.25], 0.25)
            .pause(0.3)
            .release()
            .curve([0.3, 0.0, 0.4], 0.25)
            .curve([0.45, 0.3, 0.25], 0.25)
            .grasp("part")
            .curve([0.45, 0.3, 0.3], 0.25)
            .release();
        cycles += 1;
    }
    let mut d = b.build();
    let n = ((seconds * 100.0) as usize).min(d.len());
    d.times.truncate(n);
    d.ee.truncate(n);
    d.gripper.truncate(n);
    d.detector.truncate(n);
    for o in &mut d.objects {
        o.poses.truncate(n);
    }
    d.events.retain(|e| e.frame < n);
    d
}

fn detector(c: &mut Criterion) {
    let d = demo(1000.0);
    let positions: Vec<_> = d.ee.iter().map(|p| p.translation.vector).collect();
    let mut group = c.benchmark_group("detector");
    group.throughput(Throughput::Elements(positions.len() as u64));
    group.bench_function("push_per_frame", |b| {
        b.iter(|| {
            let mut det = Detector::new(Calibration::default());
            for (t, p) in d.times.iter().zip(&positions) {
                black_box(det.push(*t, *p));
            }
            det.constrained()
        })
    });
    group.finish();
}

fn okl_scaling(c: &mut Criterion) {
    let mut group = c.benchmark_group("okl_frames");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for frames in [1_000usize, 10_000, 100_000, 1_000_000] {
        let d = demo(frames as f64 / 100.0);
        group.throughput(Throughput::Elements(d.len() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(frames), &d, |b, d| {
            b.iter(|| learn_spec(Method::Akl, d, None, &LearnOptions::default()))
        });
    }
    group.finish();
}

fn okl_vs_macl(c: &mut Criterion) {
    let mut group = c.benchmark_group("okl_vs_macl");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for seconds in [10.0, 60.0, 600.0] {
        let d = demo(seconds);
        for method in [Method::Akl, Method::Macl] {
            let id = BenchmarkId::new(method.name(), format!("{seconds}s"));
            group.bench_with_input(id, &d, |b, d| {
                b.iter(|| learn_spec(method, d, None, &LearnOptions::default()))
            });
        }
    }
    group.finish();
}

/// The fitting-error signal OKL denoises: every frame's distance from the line fitted to the
/// first detected run of a demo `frames` long.
fn fitting_error_signal(frames: usize) -> Vec<f64> {
    let d = demo(frames as f64 / 100.0);
    let positions: Vec<_> = d.ee.iter().map(|p| p.translation.vector).collect();
    let first = runs(&d.detector)[0].clone();
    let line = fit_line(&positions[first]).expect("a detected line");
    fitting_errors(&positions, 0..=positions.len() - 1, &line)
}

/// A signal on which the direct algorithm takes quadratic time: y_k = 1/(k+1) with λ = 0.5,
/// found by timing candidate signals at doubling lengths (ramps, square roots, logarithms,
/// alternations, spikes): the harmonic decay grows 4.5× per doubling. Every restart after a
/// jump rescans nearly all of the rest of the signal.
fn worst_case_signal(samples: usize) -> Vec<f64> {
    (0..samples).map(|k| 1.0 / (k + 1) as f64).collect()
}

fn tvd_throughput(c: &mut Criterion) {
    let mut group = c.benchmark_group("tvd");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(3));
    let lambda = LearnOptions::default().okl.tvd_lambda;
    for samples in [1_000usize, 10_000, 100_000] {
        let y = fitting_error_signal(samples);
        group.throughput(Throughput::Elements(y.len() as u64));
        group.bench_with_input(BenchmarkId::new("fitting_error", samples), &y, |b, y| {
            b.iter(|| akl_learn::okl::denoise(y, lambda))
        });
    }
    for samples in [1_000usize, 2_000, 4_000] {
        let y = worst_case_signal(samples);
        group.throughput(Throughput::Elements(samples as u64));
        group.bench_with_input(BenchmarkId::new("worst_case", samples), &y, |b, y| {
            b.iter(|| akl_learn::okl::denoise(y, 0.5))
        });
    }
    group.finish();
}

criterion_group!(benches, detector, okl_scaling, okl_vs_macl, tvd_throughput);
criterion_main!(benches);
