// Benchmark of the fit and diagnosis (issue 4).
