//! Learning speed: the online detector per frame, OKL against demonstration length, and OKL
//! against the mACL baseline on the same demonstrations (thesis §4.6.8).
//!
//! Run with `cargo bench -p akl-learn --bench learning`; results are in BENCHMARKS.md.

use akl_learn::calibration::Calibration;
use akl_learn::demo::Answer;
use akl_learn::detector::Detector;
use akl_learn::okl::synth::DemoBuilder;
use akl_learn::{learn_spec, Demo, LearnOptions, Method};
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
            for p in &positions {
                black_box(det.push(*p));
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

criterion_group!(benches, detector, okl_scaling, okl_vs_macl);
criterion_main!(benches);
