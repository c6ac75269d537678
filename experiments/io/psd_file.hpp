// Sieve-table files: a PSD as a user copies it from a lab sheet, in TOML or as a CSV sheet.
//
// Design note. The engine never sees TOML (sim::PsdSpec is plain), so this is the one place that
// turns a [psd] table into a spec, whether it is a file of its own (data/psd/*.toml) or a table
// embedded in a scene file. The reader is strict: an unknown key (a typo such as "dmax_mm") is an
// error rather than a silently ignored setting, and every error names the file, the field and the
// offending value. The table itself is checked by sim::resolve_psd, whose message is passed on
// with the file and the keys it concerns. Sizes in the file are in millimetres, as on lab sheets;
// the spec is in metres.
//
//   [psd]
//   name = "..."                  # optional
//   provenance = "..."            # optional: where the numbers come from
//   assumption = "..."            # optional: what is assumed rather than measured
//   sieve_mm = [0.5, 1.0, 2.0]    # sieve openings [mm], strictly increasing
//   passing_percent = [10, 40, 100]  # cumulative percent passing by mass, reaching 100
//   d_max_mm = 2.0                # optional scalping size [mm]; default the largest sieve
//   d_min_mm = 1.0                # optional lower cut-off [mm]; default the smallest sieve
//   fines = "renormalise"         # optional: "renormalise" (default) or "drop"
//   interval_sd_fraction = 0.1667 # optional: sd of the clipped normal / interval width
//
// A file whose name ends in .csv is a sieve sheet as a spreadsheet exports it, read by the same
// reader into the same spec and checked by the same rules: lines starting with '#' are notes
// (kept as the table's provenance), the header is two columns (in either order; any other column
// is refused, naming it and the nearest known one)
//   sieve_mm,passing_percent              the cumulative percent passing by mass, or
//   sieve_mm,retained_percent             the percent of the mass retained on each sieve, or
//   sieve_mm,cumulative_retained_percent  the cumulative percent retained,
// and each row is one sieve: its opening [mm] and its value. Percent retained is converted to
// percent passing (passing at a sieve = 100 - what it and the sieves above it retain), and the
// PsdFile's note says so. The cuts (d_min, d_max) and the fines policy of a CSV sheet are the
// scene's (sample.d_min_mm, sample.d_max_mm); its name is the file's stem.
//
// Either form may list its sieves finest first or coarsest first (a lab sheet often starts at
// the top sieve): sizes strictly decreasing are read in reverse, and the note says so.
#pragma once

#include <string>

#include "sim/psd.hpp"

namespace reposetwin::experiments {

/// A sieve table read from a file, with its description.
struct PsdFile {
  std::string source;      // file the table came from (for messages and result files)
  std::string name;        // [psd].name, or empty
  std::string provenance;  // [psd].provenance, or empty
  std::string assumption;  // [psd].assumption, or empty
  std::string note;        // how the file was read when not as written (its order, percent
                           // retained converted), or empty; runs print it with their plan
  sim::PsdSpec spec;       // sizes in metres
};

/// The one rule for relative paths, as the README, `reposetwin keys` and docs/scene.md state it.
inline constexpr const char* kRelativePathRule =
    "A relative path written in a file (sample.psd_file in a scene, a campaign's scene, "
    "overrides and target_photos, a test sheet's scene, photo and photo_camera) is relative to "
    "that file's folder; a path typed on the command line, --set, --tests, --sieve and --scene "
    "included, is relative to the working folder.";

/// The header of a CSV sieve sheet.
inline constexpr const char* kCsvHeader = "sieve_mm,passing_percent";

/// Whether `path` is read as a CSV sieve sheet (its extension is .csv, any case).
bool is_csv_sheet(const std::string& path);

/// Reads a sieve-table file: a CSV sieve sheet (is_csv_sheet), or TOML whose only top-level
/// table is [psd]. Throws std::runtime_error naming the file (and line) for a missing file or a
/// TOML syntax error, and std::invalid_argument (InputError for a CSV sheet) naming the file,
/// the line, the field or column and the value for bad content.
PsdFile read_psd_file(const std::string& path);

}  // namespace reposetwin::experiments
