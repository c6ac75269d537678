#include "experiments/report/format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

namespace reposetwin::experiments::report {

namespace {
std::string printf_double(const char* pattern, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, pattern, v);
  return buf;
}
}  // namespace

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string fixed_or_dash(const nlohmann::json& v, int digits) {
  return v.is_number() ? fixed(v.get<double>(), digits) : std::string("-");
}

bool interval_open_at(const nlohmann::json& result, std::size_t i) {
  const nlohmann::json& o = result.value("interval_open", nlohmann::json());
  return o.is_array() && o.size() > i && o[i].is_boolean() && o[i].get<bool>();
}

std::string sig3(const nlohmann::json& v) {
  return v.is_number() ? printf_double("%.3g", v.get<double>()) : std::string("-");
}

std::string sig3_or_dash(double v) {
  return std::isnan(v) ? std::string("-") : printf_double("%.3g", v);
}

std::string sig3_or_dash(const std::optional<double>& v) {
  return v ? sig3_or_dash(*v) : std::string("-");
}

std::string as_printed(const nlohmann::json& v) {
  return v.is_number() ? printf_double("%.6g", v.get<double>()) : std::string("-");
}

std::string mean_sd(double mean, double sd, int digits) {
  return fixed(mean, digits) + " \u00b1 " + fixed(sd, digits);
}

std::string path_for_page(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (p.is_relative()) return path;
  const fs::path rel = p.lexically_normal().lexically_relative(fs::current_path());
  if (!rel.empty() && *rel.begin() != "..") return rel.string();
  return p.filename().string();
}

std::string paths_for_page(const std::string& text) {
  const std::string stops = " \t\n:,;)'\"";
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const bool starts_word =
        i == 0 || std::string(" \t\n('\"").find(text[i - 1]) != std::string::npos;
    if (text[i] != '/' || !starts_word) {
      out += text[i++];
      continue;
    }
    std::size_t j = i;
    while (j < text.size() && stops.find(text[j]) == std::string::npos) ++j;
    out += path_for_page(text.substr(i, j - i));
    i = j;
  }
  return out;
}

std::string short_key(const std::string& key) {
  const std::string last = key.substr(key.rfind('.') + 1);
  return last == "rolling_friction" ? "mu_r" : last;
}

namespace {

// A case's label in pieces: a prediction's name ("sample4: ", or "") and its numeric inputs as
// "name value", each said once, in the overrides' order.
struct LabelParts {
  std::string prefix;
  std::vector<std::string> inputs;
};

LabelParts label_parts(const std::string& name, const nlohmann::json& overrides) {
  LabelParts l;
  std::set<std::string> said;
  std::string first_key;
  for (const auto& [key, value] : overrides.items()) {
    if (!value.is_number()) continue;
    const std::string part = short_key(key) + " " + sig3(value);
    if (!said.insert(part).second) continue;
    if (first_key.empty()) first_key = key.substr(key.rfind('.') + 1);
    l.inputs.push_back(part);
  }
  // Campaign cases of a calibration are named predict_<prediction>_<key>_<value>.
  const std::string predict = "predict_";
  if (!l.inputs.empty() && name.rfind(predict, 0) == 0) {
    const std::size_t end = name.find("_" + first_key + "_", predict.size());
    if (end != std::string::npos) l.prefix = name.substr(predict.size(), end - predict.size()) + ": ";
  }
  return l;
}

std::string joined(const std::vector<std::string>& parts) {
  std::string out;
  for (const std::string& p : parts) out += (out.empty() ? "" : ", ") + p;
  return out;
}

}  // namespace

std::string case_label(const std::string& name, const nlohmann::json& overrides) {
  const LabelParts l = label_parts(name, overrides);
  return l.inputs.empty() ? name : l.prefix + joined(l.inputs);
}

std::vector<std::string> case_labels(
    const std::vector<std::pair<std::string, nlohmann::json>>& cases) {
  std::vector<LabelParts> parts;
  std::map<std::string, std::size_t> count;  // input -> cases that have it
  for (const auto& [name, overrides] : cases) {
    parts.push_back(label_parts(name, overrides));
    for (const std::string& p : parts.back().inputs) ++count[p];
  }
  std::vector<std::string> out;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    std::vector<std::string> kept;
    for (const std::string& p : parts[i].inputs)
      if (cases.size() < 2 || count[p] < cases.size()) kept.push_back(p);
    out.push_back(kept.empty() ? case_label(cases[i].first, cases[i].second)
                               : parts[i].prefix + joined(kept));
  }
  return out;
}

}  // namespace reposetwin::experiments::report
