//! One `Axis::step` in Operation enabled, csp streaming (the cyclic hot path of every axis).
//!
//! Run with `cargo bench --bench axis_step`; criterion reports the time per step.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use ecdrive::cia402::{
    Axis, AxisConfig, DriveCaps, ErrorCode, Feedback, OperationMode, StatusWord, SupportedModes,
};

fn streaming_axis() -> (Axis, Feedback) {
    let caps = DriveCaps {
        state_skipping: true,
        transition_16: false,
        position_mode_switch_needs_zero_speed: true,
        supported_modes: SupportedModes::ALL_STANDARD,
        ..DriveCaps::CIA402
    };
    let csp = OperationMode::CyclicSyncPosition;
    let config = AxisConfig::for_cycle_time(&caps, Duration::from_micros(250), csp);
    let mut axis = Axis::new(caps, config).expect("valid configuration");
    let fb = Feedback {
        statusword: StatusWord::from_raw(0x1237),
        mode_display: Some(csp),
        position: Some(1_000_000),
        velocity: Some(0),
        torque: Some(0),
        error_code: Some(ErrorCode(0)),
        zero_speed: Some(true),
    };
    axis.request_enable().expect("no fault");
    for _ in 0..4 {
        axis.step(&fb);
    }
    while axis.poll_event().is_some() {}
    assert!(axis.status().streaming, "the bench needs a streaming axis");
    (axis, fb)
}

fn bench_step(c: &mut Criterion) {
    let (mut axis, mut fb) = streaming_axis();
    let mut target: i32 = 1_000_000;
    c.bench_function("Axis::step csp streaming", |b| {
        b.iter(|| {
            target = target.wrapping_add(16);
            // The application's set-point and the drive's feedback change every cycle.
            axis.set_position(black_box(target)).expect("streaming");
            fb.position = Some(target.wrapping_sub(3));
            let out = axis.step(black_box(&fb));
            black_box(out)
        })
    });
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
