#pragma once
/// \file frame_plot.hpp
/// The per-frame time plot of an interactive cutting run (issue 17, "Output"): per solve (a path
/// segment or a sweep triangle: scene::CutStepRow after the initial solve) the cut, the solver
/// update (column replacements and augmented solve, incl. a §3.6 swap) and frame = cut + update, in
/// wall milliseconds on a log axis (values below 0.1 ms drawn at 0.1 ms), with the 33 ms frame
/// budget dashed. `incise run` writes it beside the trace CSV of an interactive cutting run
/// (docs/scenes.md, `csv`). The times are reported, not asserted (the plot says so).

#include <incise/scene/scene_runner.hpp>

#include <string>

namespace incise::certify {

/// The frame budget drawn in the plot: 33 ms per frame (30 Hz), issue 17's target median.
inline constexpr double kFrameBudgetMs = 33.0;

/// A standalone SVG document (certify::svg_line_plot) of `result.cut_steps` as in the file
/// comment; "no data" when the run has no step after the initial solve.
std::string frame_time_svg(const scene::SceneRunResult& result, const std::string& title);

/// Where `incise run` writes the plot for a trace CSV: `path` with a final ".csv" replaced by
/// "_frames.svg" (appended when `path` does not end in ".csv").
std::string frame_plot_path(const std::string& csv_path);

}  // namespace incise::certify
