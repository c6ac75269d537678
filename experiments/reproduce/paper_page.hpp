// The paper page: every item of the paper's index beside what we have for it.
//
// Design. One HTML page (the report's mustache skeleton, tables and gnuplot plots: report/) over
// a `reposetwin paper` results folder. Each item gets a section: the paper's stated values (the
// index's paper_points, as points on the plot and in words) or its shape-only trend, our points
// with their seed spread where results exist (a campaign: mean +- sd of the item's angle per
// case over the runs that formed a pile, the others counted by reason; a calibration: the
// calibrated mu_r with its interval and pile runs, the jam rate per mu_r, and the predictions; a
// derived item: its sources' calibrated mu_r against d_max), "not yet run" where nothing exists,
// and the reductions and cost of the item from its run plan. The page only reads result files;
// it never reruns anything, and shows numbers in tables, never raw JSON. Links are relative to
// the page, so the results folder travels with it.
#pragma once

#include <string>

#include "experiments/reproduce/paper_index.hpp"

namespace reposetwin::experiments {

/// Builds OUT/paper_page/index.html (+ its plots) from the results under OUT and returns its
/// path. An earlier page is replaced only with `force` (InputError otherwise).
std::string build_paper_page(const PaperIndex& index, const std::string& out_dir, bool force);

}  // namespace reposetwin::experiments
