// Numbers as the report pages print them: one set of formatting functions for every page (the
// campaign, calibration and comparison report and the loop's page).
//
// Design note. Each function names a convention rather than a printf pattern, so a table states
// what its numbers are: a measured quantity with a fixed number of decimals, a derived statistic
// to three significant digits, or the paper's own values as printed (never padded with digits
// the paper did not give). A value that is not a number (a JSON null: nothing measured) prints
// as "-".
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace reposetwin::experiments::report {

/// `v` with `digits` decimals ("%.*f"): angles and coefficients we measured.
std::string fixed(double v, int digits = 2);

/// fixed() of a JSON number, "-" otherwise.
std::string fixed_or_dash(const nlohmann::json& v, int digits = 2);

/// Whether a result's mu_r interval (`interval_open`, a pair of booleans) is open at end i
/// (0 low, 1 high): the search stopped at the grid's end there.
bool interval_open_at(const nlohmann::json& result, std::size_t i);

/// Three significant digits ("%.3g"), "-" for a non-number: the loop's statistics.
std::string sig3(const nlohmann::json& v);

/// sig3 of a number read back from a result file, "-" for NaN (written as null: no value) and
/// for none.
std::string sig3_or_dash(double v);
std::string sig3_or_dash(const std::optional<double>& v);

/// The shortest form of the paper's numbers as printed (0.15, 3.35, 200), "-" for a non-number.
std::string as_printed(const nlohmann::json& v);

/// "mean ± sd" with fixed() decimals.
std::string mean_sd(double mean, double sd, int digits = 2);

/// A file path as a page shows it: a relative path as given, an absolute one relative to the
/// working folder when it lies below it, else its file name (a reader's machine has not the
/// builder's folders; the record keeps the full path).
std::string path_for_page(const std::string& path);

/// Free text (an error message recorded in a result) as a page shows it: every absolute path in
/// it, a run of characters from a '/' that starts a word up to a space, ':', ',', ';', ')' or a
/// quote, shown by path_for_page.
std::string paths_for_page(const std::string& text);

/// A short name of a scene key for labels: "mu_r" for a rolling friction, else the key's last
/// dotted part (contacts.rock-rock.rolling_friction -> mu_r, sample.d_min_mm -> d_min_mm).
std::string short_key(const std::string& key);

/// A case as a person reads it on an axis or in a table: its overrides as "name value" with three
/// significant digits ("mu_r 0.399"; keys with one short name and one value said once), prefixed
/// by a prediction's name ("sample4: mu_r 0.365" for predict_sample4_rolling_friction_0.365...).
/// A case without numeric overrides keeps its name.
std::string case_label(const std::string& name, const nlohmann::json& overrides);

/// The labels of several cases side by side (an axis): each case_label without the "name value"
/// parts every case shares, which say nothing about the difference (a user's calibration sets
/// the funnel and mass on every case). A label left empty keeps its case_label.
std::vector<std::string> case_labels(
    const std::vector<std::pair<std::string, nlohmann::json>>& cases);

}  // namespace reposetwin::experiments::report
