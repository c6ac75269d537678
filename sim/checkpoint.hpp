// Checkpoints: the whole State in one binary file, from which a run resumes bit-identically.
//
// The particle and body arrays are written by iterating their field lists, so a new field is
// saved without touching this code. (The clump templates are the Model's, not saved: the resumed
// world must be built with the same templates.) The neighbor list (with every contact's spring history) is saved
// as it is, so the resumed run rebuilds it at exactly the same steps as an uninterrupted one.
// Every byte of a file is a value's (a struct with padding is written field by field), so one
// state always writes one file and checkpoints can be compared byte for byte.
// Files are written to a temporary name and renamed into place (never half a checkpoint), and end
// with a checksum of every byte before it, verified before anything is parsed: a damaged file
// (a flipped byte, a partial copy) is refused, never resumed into a different result.
#pragma once

#include <string>

#include "sim/world.hpp"

namespace reposetwin::sim {

/// Writes the world's state (and the time step it was made with) to `path` atomically.
void write_checkpoint(const World& world, const std::string& path);

/// Replaces the world's state by the checkpoint's. Throws std::runtime_error naming the path if
/// the file is unreadable, truncated, damaged (its checksum), of another format, or made with
/// another time step or wall count.
void read_checkpoint(World& world, const std::string& path);

}  // namespace reposetwin::sim
