//! Project tasks: `cargo xtask bench`.
//!
//! `bench` prints one line per figure, `name value unit`.

use std::time::Instant;

use hyst_model::Oscillator;
use hyst_sim::excitation::{Multisine, white_noise};
use hyst_sim::{Input, SimOptions, simulate};

fn usage() -> ! {
    eprintln!("usage: cargo xtask bench");
    std::process::exit(2)
}

/// Best of `reps` wall times of `f`, in seconds.
fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn bench() {
    let n = 1usize << 20;
    let fs = 750.0;
    let opts = SimOptions::default();
    let steps = ((n - 1) * opts.oversample) as f64;
    let model = Oscillator::benchmark();

    let u = white_noise(n, 50.0, 1).expect("valid rms");
    let t = best_of(3, || {
        simulate(&model, Input::Sampled(&u), fs, n, &opts).expect("stable")
    });
    println!("rk4_ns_per_step {:.2} ns", t / steps * 1e9);

    let period = Multisine::benchmark(50.0)
        .generate(1)
        .expect("valid multisine");
    let t = best_of(3, || {
        simulate(&model, Input::Periodic(&period), fs, n, &opts).expect("stable")
    });
    println!("rk4_ns_per_step_periodic_input {:.2} ns", t / steps * 1e9);
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("bench") => bench(),
        _ => usage(),
    }
}
