// The closed loop's page: loop.json as an HTML page with tables and gnuplot plots.
//
// Design note. The loop (loop/loop.hpp) sits below report/ and does not call it: the command
// gives this function to the loop as its page writer (LoopSettings::page), so the loop still
// writes the page just before loop.json, and a finished loop.json means a finished page. The page
// reads loop.json through the one reader of the loop's records (loop_record_from_json) and
// renders the record, so the loop's own page proves that its loop.json reads back. It uses
// the report's page skeleton, tables, plotting and number formats (report.hpp).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/loop/loop_records.hpp"

namespace reposetwin::experiments {

/// Writes OUT/index.html and its plots (gnuplot) from a loop.json, read into its LoopRecord by
/// loop_record_from_json. Throws InputError naming OUT/loop.json and the JSON pointer of a field
/// that is missing or of the wrong type, std::runtime_error when a file cannot be written.
void write_loop_html(const nlohmann::json& loop, const std::string& out_dir);

/// Writes OUT/index.html and its plots from the loop's record, as write_loop_html does.
void write_loop_page(const LoopRecord& loop, const std::string& out_dir);

}  // namespace reposetwin::experiments
