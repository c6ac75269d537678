// fuzz_support: what every harness shares.
//
// Design note. Each harness feeds one reader the bytes a fuzzer (libFuzzer, under clang) or a
// replay of the committed corpus (any compiler, run by ctest) gives it, the way a user's file
// reaches it: as a file on disk with a name. The oracle is the project's promise about bad input,
// not only "no crash": a refusal is an exception whose message names the file (the command line
// prints it and exits non-zero: InputError for a reader, std::invalid_argument or
// std::runtime_error for an image vision cannot measure); anything else (a message without the
// file, such as a library's own assertion or a JSON type error, a non-standard exception, a
// crash, a sanitizer report, a hang) is a finding and aborts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>
#include <typeinfo>

namespace reposetwin::fuzz {

/// Writes the input to a file of this name in a per-process temporary folder; returns its path.
std::string write_input(const std::uint8_t* data, std::size_t size, const std::string& name);

/// Prints `what` as a finding and aborts (libFuzzer then keeps the input as a crash).
[[noreturn]] void finding(const std::string& what);

/// Runs `read`. An exception whose message names `file` (a path or a file name) is a clear
/// refusal; any other exception is a finding.
template <class Read>
void expect_clear_refusal(const std::string& file, Read&& read) {
  try {
    read();
  } catch (const std::exception& e) {
    if (std::string(e.what()).find(file) == std::string::npos)
      finding(std::string("the refusal (") + typeid(e).name() + ") does not name " + file + ": " +
              e.what());
  } catch (...) {
    finding("a non-standard exception");
  }
}

}  // namespace reposetwin::fuzz
