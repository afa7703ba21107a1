// Benchmark of the Allan deviation (issue 4); see allan_bench notes.
