// The paper comparison's section of a report page (paper_comparison() itself is public, in
// report.hpp, with the design note): its table, caption and measured-against-simulated plot.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace reposetwin::experiments::report {

/// The rendered section for a paper_comparison() result; writes its plot (and the plot's data
/// and script) into `out`.
std::string comparison_section(const nlohmann::json& cmp, const std::filesystem::path& out);

}  // namespace reposetwin::experiments::report
