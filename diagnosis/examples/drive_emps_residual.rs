//! Where the EMPS validation run's unexplained force lies: the residual
//! of the diagnosed drive model (fitted on the estimation run, three
//! effects) by frequency band and by 2 s stretch, next to the estimation
//! run's own held-out residual, and its regression on the known external
//! force at several lags.
//! `cargo run --release -p limb-diagnosis --example drive_emps_residual`
use limb_diagnosis::plant::drive::{read, DriveModel, CUTOFF};
use limb_diagnosis::{select, HoldOut, Model, Options, Problem};
use rustfft::{num_complex::Complex, FftPlanner};

/// Share of the residual's power (mean removed) per band [Hz].
fn bands(r: &[f64], interval: f64) -> String {
    let n = r.len();
    let mean = r.iter().sum::<f64>() / n as f64;
    let mut buffer: Vec<Complex<f64>> = r.iter().map(|v| Complex::new(v - mean, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    let power: Vec<f64> = buffer[1..n / 2].iter().map(|c| c.norm_sqr()).collect();
    let total: f64 = power.iter().sum();
    let edges = [0.0, 0.7, 1.5, 4.0, 10.0, 20.0, 30.0, 50.0];
    let rms = (r.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let mut line = format!("rms {rms:.2} N, mean {mean:.2} N; power by band:");
    for w in edges.windows(2) {
        let share: f64 = power
            .iter()
            .enumerate()
            .filter(|(k, _)| (w[0]..w[1]).contains(&((*k + 1) as f64 / (n as f64 * interval))))
            .map(|(_, p)| p)
            .sum::<f64>()
            / total;
        line += &format!(" {}-{} Hz {:.1} %,", w[0], w[1], 100.0 * share);
    }
    line
}

fn residual(model: &DriveModel, predicted: &limb_diagnosis::Series) -> Vec<f64> {
    let observed = model.observed().column(0);
    observed
        .iter()
        .zip(predicted.column(0))
        .map(|(o, p)| o - p)
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real/emps");
    let (fit, held) = (
        read(&dir.join("estimation.csv"))?,
        read(&dir.join("validation.csv"))?,
    );
    let (a, b) = (
        DriveModel::new(&fit, CUTOFF)?,
        DriveModel::new(&held, CUTOFF)?,
    );
    let options = Options {
        max_effects: 3,
        ..Options::default()
    };
    let interval = b.times()[1] - b.times()[0];
    let two = select(&Problem::two_runs(&a, &b), &options, &|_| {})?;
    let r = residual(&b, two.predictions.chosen.as_ref().ok_or("no prediction")?);
    println!("validation (held out whole): {}", bands(&r, interval));
    let split = select(&Problem::split(&a, HoldOut::default())?, &options, &|_| {})?;
    let r2 = residual(
        &a,
        split.predictions.chosen.as_ref().ok_or("no prediction")?,
    );
    println!(
        "estimation (its own held-out blocks and fit blocks): {}",
        bands(&r2, interval)
    );
    let per = |x: &[f64]| -> Vec<String> {
        let per_block = (2.0 / interval) as usize;
        x.chunks(per_block)
            .map(|c| {
                format!(
                    "{:.1}",
                    (c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64).sqrt()
                )
            })
            .collect()
    };
    println!("validation rms per 2 s [N]: {}", per(&r).join(" "));
    println!("estimation rms per 2 s [N]: {}", per(&r2).join(" "));
    let f = held.f_ext.ok_or("validation has no f_ext")?;
    let step = ((interval / 1e-3).round() as usize).max(1);
    let mean_r = r.iter().sum::<f64>() / r.len() as f64;
    let mut line = String::from("residual regressed on f_ext(t - lag) [N/N]:");
    for lag in [-250i64, -50, -10, 0, 10, 50, 250] {
        let x: Vec<f64> = (0..r.len())
            .map(|i| f[(i as i64 * step as i64 - lag).clamp(0, f.len() as i64 - 1) as usize])
            .collect();
        let mean_x = x.iter().sum::<f64>() / x.len() as f64;
        let c = x
            .iter()
            .zip(&r)
            .map(|(x, r)| (x - mean_x) * (r - mean_r))
            .sum::<f64>()
            / x.iter().map(|x| (x - mean_x).powi(2)).sum::<f64>();
        line += &format!(" {lag} ms {c:.2},");
    }
    println!("{line}");
    Ok(())
}
