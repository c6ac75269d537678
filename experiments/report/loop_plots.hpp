// The loop page's residual plots: each test's residual before and after the chosen effects,
// against each condition the tests differ in (text conditions as categories, the size
// distribution as series and categories of its own), drawn by gnuplot.
//
// Design note. A residual plot against a condition every test has at one value is a single
// column of points that tells nothing, so constant_conditions names those and the page states
// them instead. The plots are written into the page's folder with their data and scripts, so a
// reader can redraw them; a folder's earlier plots are removed first, since a condition plotted
// then may be constant now.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "experiments/loop/loop_records.hpp"
#include "experiments/report/html.hpp"

namespace reposetwin::experiments::report {

/// The conditions every test has at one value, by name, with that value as the page prints it
/// (numbers to three significant digits); the PSD's set: keys are left to the PSD's own plot.
std::map<std::string, std::string> constant_conditions(const std::vector<LabTest>& tests);

/// Writes the residual plots of `loop` into `dir` (each one's data, gnuplot script and PNG; a
/// failing gnuplot throws, gnuplot.hpp), after removing the folder's earlier residual_* files; the figures
/// drawn, named relative to the page ("plots/residual_<condition>.png").
std::vector<Figure> residual_figures(const LoopRecord& loop, const std::filesystem::path& dir);

}  // namespace reposetwin::experiments::report
