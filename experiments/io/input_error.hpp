// The one exception type for bad input: a scene, campaign, CSV, photo or sidecar that cannot be
// used as given. Its message names the file, the key (as the user wrote it) and the value, and
// the command line turns it into a clear error and a non-zero exit before anything runs.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

namespace reposetwin::experiments {

/// A bad input file or value: the message names the file, the key and the value. A scene
/// parser's error also carries the dotted key on its own, so a caller that changed that key
/// (a --set) can say so.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
  InputError(const std::string& what, std::string key)
      : std::invalid_argument(what), key_(std::move(key)) {}
  /// The dotted key the message is about ("" when the message is not about one key).
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

}  // namespace reposetwin::experiments
