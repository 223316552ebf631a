// Pure summary statistics for short series of measurements (response times).

/** Finite numbers only. */
function finite(values) {
  return values.map(Number).filter(Number.isFinite);
}

/** Arithmetic mean; NaN for no values. */
export function mean(values) {
  const numbers = finite(values);
  return numbers.length ? numbers.reduce((sum, v) => sum + v, 0) / numbers.length : NaN;
}

/** Nearest-rank percentile (p in 0..100); NaN for no values. */
export function percentile(values, p) {
  const numbers = finite(values).sort((a, b) => a - b);
  if (!numbers.length) return NaN;
  const rank = Math.ceil((Math.min(100, Math.max(0, p)) / 100) * numbers.length);
  return numbers[Math.max(0, rank - 1)];
}

/** {count, last, mean, p95} of the last `n` values. */
export function summarize(values, n = 50) {
  const window = finite(values).slice(-n);
  return { count: window.length, last: window.length ? window[window.length - 1] : NaN, mean: mean(window),
    p95: percentile(window, 95) };
}
