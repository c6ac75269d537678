// Plots for the report pages: gnuplot (pngcairo) run on a script written beside its data.
//
// Design note. The script and data files stay in the report folder, so a plot can be restyled
// and rerun by hand without the twin. gnuplot is started through experiments/io/process.hpp
// (an argument vector, never a shell). A missing or failing gnuplot is an error naming the
// script: a page never stands silently without a figure it was meant to show.
#pragma once

#include <filesystem>
#include <string>

namespace reposetwin::experiments::report {

/// Writes `script` to `script_path` and runs gnuplot on it in the script's folder. Throws
/// std::runtime_error naming gnuplot and the script when the script cannot be written, gnuplot
/// cannot be started or fails (its output is then kept in SCRIPT.log), or `png` is missing or
/// empty afterwards (an empty one is removed).
void run_gnuplot(const std::filesystem::path& script_path, const std::string& script,
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
