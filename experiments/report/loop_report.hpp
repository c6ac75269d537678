// The closed loop's page: loop.json as an HTML page with tables and gnuplot plots.
//
// Design note. The loop (loop/loop.hpp) sits below report/ and does not call it: the command
// gives this function to the loop as its page writer (LoopSettings::page), so the loop still
// writes the page just before loop.json, and a finished loop.json means a finished page. It uses
// the report's page skeleton, tables, plotting and number formats (report.hpp).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace reposetwin::experiments {

/// Writes OUT/index.html and its plots (gnuplot) from a loop.json. Throws std::runtime_error when
/// a file cannot be written.
void write_loop_html(const nlohmann::json& loop, const std::string& out_dir);

}  // namespace reposetwin::experiments
