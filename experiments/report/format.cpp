#include "experiments/report/format.hpp"

#include <cstdio>

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

std::string sig3(const nlohmann::json& v) {
  return v.is_number() ? printf_double("%.3g", v.get<double>()) : std::string("-");
}

std::string as_printed(const nlohmann::json& v) {
  return v.is_number() ? printf_double("%.6g", v.get<double>()) : std::string("-");
}

std::string mean_sd(double mean, double sd, int digits) {
  return fixed(mean, digits) + " \u00b1 " + fixed(sd, digits);
}

}  // namespace reposetwin::experiments::report
