// Plots for the report pages: gnuplot (pngcairo) run on a script written beside its data.
//
// Design note. The script and data files stay in the report folder, so a plot can be restyled
// and rerun by hand without the twin. A missing or failing gnuplot is not an error: the page
// says it has no plot, and everything else in the report still stands.
#pragma once

#include <filesystem>
#include <string>

namespace reposetwin::experiments::report {

/// Writes `script` to `script_path` and runs gnuplot on it. Returns whether gnuplot succeeded
/// and `png` is not empty (an empty one is removed). Throws std::runtime_error when the script
/// cannot be written.
bool run_gnuplot(const std::filesystem::path& script_path, const std::string& script,
                 const std::filesystem::path& png);

/// `text` as a gnuplot single-quoted string ('mu_r (EDEM''s)'): a quote in a label must not end
/// the string and the script with it.
std::string gnuplot_string(const std::string& text);

/// The first lines of a script drawing a `width` x `height` PNG to `png` (by its file name: the
/// script runs in the PNG's folder); `enhanced` false
/// prints labels as written (underscores in case names stay underscores).
std::string png_terminal(const std::filesystem::path& png, int width, int height,
                         bool enhanced = true);

}  // namespace reposetwin::experiments::report
