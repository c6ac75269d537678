// The one exception type for bad input: a scene, campaign, CSV, photo or sidecar that cannot be
// used as given. Its message names the file, the key (as the user wrote it) and the value, and
// the command line turns it into a clear error and a non-zero exit before anything runs.
#pragma once

#include <stdexcept>

namespace reposetwin::experiments {

/// A bad input file or value: the message names the file, the key and the value.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

}  // namespace reposetwin::experiments
