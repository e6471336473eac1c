#pragma once
// Modified Newton's test, shared by the EFG (EfgOptions::refactor_contraction) and the LRPIM
// (LrpimProblem::refactor_contraction): Newton keeps the factors of an earlier tangent while the updates on them
// contract the residual fast enough, and takes the current tangent when they do not (docs/MESHLESS.md §2, "Tangent
// reuse"; docs/LRPIM.md, "Time stepping"). Pure function; thread-safe.

namespace meshless {

/// Whether the kept factors must give way to the current tangent at ||R|| = `rn`, the last update having started at
/// `last`. `run_start` is ||R|| where the run of `run_length` updates on these factors that is judged began (the EFG
/// judges its last update alone: run_start = last, run_length = 1; the LRPIM the step's whole run). True when the
/// last update did not reduce ||R||, when the run contracted ||R|| by less than `contraction` per update on average
/// (the geometric mean: Anderson-mixed updates contract unevenly, and one slow update in a fast run does not pay for
/// a factorisation), or when at that rate ||R|| would not reach `target` by iteration `max_iterations`. False while
/// the run has no update yet.
bool kept_factors_too_slow(double rn, double last, double run_start, int run_length, double target, int iteration,
                           double contraction, int max_iterations);

}  // namespace meshless
