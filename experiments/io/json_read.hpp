// Reading a record back from a result file with the place of any fault: a field that is missing
// or of the wrong type throws JsonFieldError carrying its JSON pointer (RFC 6901), so a reader of
// a 400 kB loop.json says "/iterations/1/joint/3/chi2: missing", not "key 'chi2' not found".
//
// Design note. Each record's from_json reads its own fields with field / number_field and its
// sub-records with nested / each; an error leaving a sub-record gets that sub-record's key (or
// index) put in front of its pointer on the way out, so no reader needs to know where it is in
// the document. The top-level reader of a file catches the error once and names the file.
#pragma once

#include <algorithm>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "experiments/io/input_error.hpp"
#include "experiments/io/suggest.hpp"

namespace reposetwin::experiments {

/// A field of a result file that is missing or of the wrong type: where it is (a JSON pointer
/// within the document read, "" for the document itself) and what is wrong with it.
class JsonFieldError : public std::runtime_error {
 public:
  JsonFieldError(std::string pointer, std::string problem)
      : std::runtime_error(pointer + ": " + problem),
        pointer_(std::move(pointer)),
        problem_(std::move(problem)) {}
  const std::string& pointer() const { return pointer_; }
  const std::string& problem() const { return problem_; }
  /// The same error one level down: `token` (a key or an index) in front of the pointer.
  JsonFieldError under(const std::string& token) const {
    return JsonFieldError("/" + escaped(token) + pointer_, problem_);
  }
  /// `token` as one reference token of a JSON pointer ("~" as "~0", "/" as "~1").
  static std::string escaped(const std::string& token) {
    std::string out;
    for (char c : token) out += c == '~' ? std::string("~0") : c == '/' ? "~1" : std::string(1, c);
    return out;
  }

 private:
  std::string pointer_, problem_;
};

namespace json_read_detail {

inline const nlohmann::json& member(const nlohmann::json& j, const char* key) {
  if (!j.is_object())
    throw JsonFieldError("", std::string("is ") + j.type_name() + ", not an object");
  const auto it = j.find(key);
  if (it == j.end()) throw JsonFieldError("/" + JsonFieldError::escaped(key), "missing");
  return *it;
}

// Runs read() on the value at `token`, putting the token in front of any error's pointer; an
// error a reader raises itself (an unknown enum word, a type nlohmann refuses) is placed there.
template <class F>
auto at_token(const nlohmann::json& v, const std::string& token, F&& read) -> decltype(read(v)) {
  try {
    return read(v);
  } catch (const JsonFieldError& e) {
    throw e.under(token);
  } catch (const nlohmann::json::exception& e) {
    throw JsonFieldError("/" + JsonFieldError::escaped(token), e.what());
  } catch (const std::invalid_argument& e) {
    throw JsonFieldError("/" + JsonFieldError::escaped(token), e.what());
  }
}

}  // namespace json_read_detail

/// Refuses a key of the object `j` that is not one of `known`: JsonFieldError at /key saying so,
/// with its value, the nearest known key (suggest.hpp) and the known keys. A strict record's
/// from_json calls it first, so a misspelt key is named rather than reported missing.
inline void known_fields(const nlohmann::json& j, std::initializer_list<const char*> known) {
  if (!j.is_object())
    throw JsonFieldError("", std::string("is ") + j.type_name() + ", not an object");
  for (const auto& [key, value] : j.items()) {
    bool ok = false;
    std::string list;
    for (const char* k : known) {
      ok = ok || key == k;
      list += (list.empty() ? "" : ", ") + std::string(k);
    }
    if (ok) continue;
    std::string shown = value.dump();
    if (shown.size() > 80) shown = shown.substr(0, 80) + "...";
    throw JsonFieldError("/" + JsonFieldError::escaped(key),
                         "is not a known key (value " + shown + ")" + did_you_mean(key, known) +
                             "; known keys: " + list);
  }
}

/// j[key] as a T; JsonFieldError at /key when it is missing or not a T.
template <class T>
T field(const nlohmann::json& j, const char* key) {
  const nlohmann::json& v = json_read_detail::member(j, key);
  try {
    return v.get<T>();
  } catch (const nlohmann::json::exception&) {
    throw JsonFieldError("/" + JsonFieldError::escaped(key),
                         std::string("has the wrong type (") + v.type_name() + ")");
  }
}

/// read(j[key]): a sub-record, whose errors' pointers get /key in front.
template <class F>
auto nested(const nlohmann::json& j, const char* key, F&& read) {
  return json_read_detail::at_token(json_read_detail::member(j, key), key, read);
}

/// read(e) of every element e of the array `a`, in order; an error's pointer gets /i.
template <class F>
auto elements(const nlohmann::json& a, F&& read) {
  if (!a.is_array())
    throw JsonFieldError("", std::string("is ") + a.type_name() + ", not an array");
  std::vector<std::decay_t<decltype(read(a))>> out;
  for (std::size_t i = 0; i < a.size(); ++i)
    out.push_back(json_read_detail::at_token(a[i], std::to_string(i), read));
  return out;
}

/// read(e) of every element e of the array j[key], in order; an error's pointer gets /key/i.
template <class F>
auto each(const nlohmann::json& j, const char* key, F&& read) {
  return nested(j, key, [&](const nlohmann::json& a) { return elements(a, read); });
}

/// A JSON number as a double, null as NaN; JsonFieldError (at the value) for anything else.
inline double number_value(const nlohmann::json& v) {
  if (v.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!v.is_number())
    throw JsonFieldError("", std::string("is ") + v.type_name() + ", not a number");
  return v.get<double>();
}

/// j[key] as a double, null as NaN (a NaN is written as null).
inline double number_field(const nlohmann::json& j, const char* key) {
  return nested(j, key, number_value);
}

/// j[key] as a double when present and not null.
inline std::optional<double> optional_number_field(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return number_field(j, key);
}

/// The array j[key] of numbers, null as NaN.
inline std::vector<double> numbers_field(const nlohmann::json& j, const char* key) {
  return each(j, key, number_value);
}

/// The array `a` of numbers, null as NaN.
inline std::vector<double> number_values(const nlohmann::json& a) {
  return elements(a, number_value);
}

/// A JSON pointer as the user reads a key: "/material/overrides/0/key" as
/// material.overrides[0].key.
inline std::string dotted_key(const std::string& pointer) {
  std::string out;
  std::size_t from = 1;
  while (from <= pointer.size()) {
    const std::size_t slash = std::min(pointer.find('/', from), pointer.size());
    const std::string token = pointer.substr(from, slash - from);
    const bool index = !token.empty() && token.find_first_not_of("0123456789") == std::string::npos;
    out += index ? "[" + token + "]" : (out.empty() ? "" : ".") + token;
    from = slash + 1;
  }
  return out;
}

/// The error `e`, met reading the document `doc` of `file`, as the InputError the user reads:
/// the file, the key as written (quoted, dotted) or "the top level", its value when it has one,
/// and what is wrong: FILE: key "mu_r" = "0.3": is string, not a number.
inline InputError file_field_error(const JsonFieldError& e, const std::string& file,
                                   const nlohmann::json& doc) {
  std::string value;
  const nlohmann::json::json_pointer p(e.pointer());
  if (doc.contains(p)) {
    value = doc.at(p).dump();
    if (value.size() > 80) value = value.substr(0, 80) + "...";
    // known_fields puts the value in its own words already.
    value = e.problem().find("(value ") == std::string::npos ? " = " + value : std::string();
  }
  const std::string where = e.pointer().empty() ? std::string("the top level")
                                                : "key \"" + dotted_key(e.pointer()) + "\"";
  return InputError(file + ": " + where + value + ": " + e.problem());
}

}  // namespace reposetwin::experiments
