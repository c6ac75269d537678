// Provenance and folder locks.
//
// Every result file says how it was made (scene, seed, time step, softened stiffness, code
// version). Results are read and written through the file layer (files.hpp, included here for
// its callers): atomic writes, inputs that are regular files of a bounded size.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "experiments/io/files.hpp"
#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {

/// The code version: project version plus `git describe` when the build ran.
std::string code_version();

/// A content hash of the sources a pile run's result depends on (the DEM, the pile test, the
/// scene inputs, the run folders, the build flags; cmake/write_version.cmake): caches of pile
/// runs are keyed by it, so a commit that leaves the engine alone finds the runs made before it.
std::string engine_version();

/// The same for a photograph of a pile and its measurement (camera, renderer, vision, photos).
std::string imaging_version();

/// UTC time now, ISO 8601 ("2026-11-22T01:02:03Z").
std::string utc_now();

/// Another process holds a folder's lock (a bad input for this one, which a caller that can
/// wait for the other, such as a shared cache, catches by type).
class FolderBusy : public InputError {
 public:
  using InputError::InputError;
};

/// An exclusive lock on a folder, held while the object lives and released by the kernel when
/// the process ends, even by SIGKILL: two processes never write one run or campaign folder.
class FolderLock {
 public:
  /// Locks DIR/NAME (created with DIR). Throws FolderBusy naming the folder and `what`
  /// ("another pile run") when another process holds it.
  FolderLock(const std::string& dir, const std::string& name, const std::string& what);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace reposetwin::experiments
