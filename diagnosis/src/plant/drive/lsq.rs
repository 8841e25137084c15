//! Linear least squares for the parameters a drive's prediction is
//! linear in: minimise Σ over the masked samples of
//! (target − Σⱼ θⱼ columnⱼ)², by the normal equations solved with
//! Gaussian elimination and partial pivoting.
//!
//! The columns are few (at most a dozen) and the samples many, so the
//! normal equations cost O(n p²) and their conditioning is kept in hand by
//! scaling every column to unit RMS first. A column that is zero on the
//! masked samples, or a singular system, gives a coefficient of 0 for the
//! dependent columns instead of a failure.

/// The θ minimising the masked sum of squares (one per column; 0 for
/// columns the data cannot determine).
pub fn solve(columns: &[&[f64]], target: &[f64], mask: &[bool]) -> Vec<f64> {
    let p = columns.len();
    let used = |i: &usize| mask.get(*i).copied().unwrap_or(false);
    let n = target.len();
    let norms: Vec<f64> = columns
        .iter()
        .map(|c| {
            let (sum, count) = (0..n.min(c.len()))
                .filter(used)
                .fold((0.0, 0usize), |(s, k), i| (s + c[i] * c[i], k + 1));
            let rms = (sum / count.max(1) as f64).sqrt();
            if rms.is_finite() && rms > 0.0 {
                rms
            } else {
                0.0
            }
        })
        .collect();
    // Augmented normal matrix [AᵀA | Aᵀb] of the scaled columns.
    let mut normal = vec![vec![0.0; p + 1]; p];
    for i in (0..n).filter(used) {
        let row: Vec<f64> = columns
            .iter()
            .zip(&norms)
            .map(|(c, s)| {
                if *s > 0.0 {
                    c.get(i).copied().unwrap_or(0.0) / s
                } else {
                    0.0
                }
            })
            .collect();
        for (j, line) in normal.iter_mut().enumerate() {
            for (k, value) in line.iter_mut().take(p).enumerate() {
                *value += row[j] * row[k];
            }
            line[p] += row[j] * target[i];
        }
    }
    let scaled = eliminate(normal);
    scaled
        .iter()
        .zip(&norms)
        .map(|(t, s)| {
            if *s > 0.0 && t.is_finite() {
                t / s
            } else {
                0.0
            }
        })
        .collect()
}

/// Solves the augmented system by Gauss–Jordan elimination with partial
/// pivoting; an unknown whose pivot falls below 1e-12 of the largest
/// diagonal (a column the others already explain) is left at 0.
fn eliminate(mut m: Vec<Vec<f64>>) -> Vec<f64> {
    let p = m.len();
    let tiny = (0..p).map(|i| m[i][i].abs()).fold(0.0, f64::max) * 1e-12;
    for column in 0..p {
        let pivot = (column..p).max_by(|a, b| m[*a][column].abs().total_cmp(&m[*b][column].abs()));
        let Some(pivot) = pivot.filter(|r| m[*r][column].abs() > tiny) else {
            continue;
        };
        m.swap(column, pivot);
        let head = m[column].clone();
        for (r, row) in m.iter_mut().enumerate() {
            if r != column {
                let factor = row[column] / head[column];
                for (v, h) in row.iter_mut().zip(&head) {
                    *v -= factor * h;
                }
            }
        }
    }
    (0..p)
        .map(|i| {
            if m[i][i].abs() > tiny {
                m[i][p] / m[i][i]
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::solve;

    #[test]
    fn recovers_a_line_and_ignores_masked_and_empty_columns() {
        let x: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let ones = vec![1.0; 100];
        let zero = vec![0.0; 100];
        let mut y: Vec<f64> = x.iter().map(|x| 3.0 * x - 2.0).collect();
        y[0] = 1e6;
        let mut mask = vec![true; 100];
        mask[0] = false;
        let theta = solve(&[&x, &ones, &zero], &y, &mask);
        assert!((theta[0] - 3.0).abs() < 1e-9 && (theta[1] + 2.0).abs() < 1e-9);
        assert_eq!(theta[2], 0.0);
    }
}
