// The one file layer: what an input, an output and a command's own folder are.
//
// Design note. Faults with files come in classes, and each class is closed here once rather
// than per command:
//  - Inputs are regular files of a bounded size. A FIFO blocks its reader until someone writes,
//    a device (/dev/zero) never ends, a directory reads as empty on Linux; all are refused
//    before a byte is read, naming the path and what it is. read_file() checks the descriptor
//    it reads (fstat after an O_NONBLOCK open), so a file swapped for a FIFO after a check
//    cannot hang it either.
//  - An output replaces only a regular file: write_file_atomic() refuses a FIFO, a device, a
//    socket, a folder or a symlink at the target (on a root shell, /dev/full is one rename
//    away). It writes a temporary in the same folder and renames it into place.
//  - A command that writes beside the user's own files (measure's overlays, loop's page,
//    loop-synth's truth) states its inputs and outputs in an OutputPlan first. The plan refuses
//    an output that is the same file as an input (by device and inode, so another spelling, a
//    hard link or a symlink is caught), two outputs at one file, a non-regular target, and an
//    existing file this program did not make unless the command was given --force.
//  - "Made by us" is known from a manifest, `.reposetwin-made.json`, that the plan keeps in
//    each folder it writes into: a file's name with the inode, size and modification time it
//    had when written. A file the user replaced or edited since no longer matches, and counts
//    as theirs. Run folders keep their own rule (experiments/pile/run_folder.hpp: a run's files
//    by name, in a folder classified as a run's), with refuse_escaping_links() below.
//  - A symlink inside a folder a command owns that leads outside it is refused before the
//    command writes there, so `images -> ~/photos` cannot aim a run's writes at another folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {

/// The largest file read_file() reads unless told otherwise [bytes].
inline constexpr std::uintmax_t kMaxReadBytes = std::uintmax_t{1} << 30;

/// Throws InputError naming `path` and the reason unless it is a regular file (a symlink to one
/// is one) of at most `max_bytes`: for a missing path, a directory, a FIFO, a socket, a device
/// and a larger file. For readers that open the file themselves (VTK, a streamed dump).
void check_input_file(const std::string& path, std::uintmax_t max_bytes = kMaxReadBytes);

/// Reads a whole regular file of at most `max_bytes`, refusing as check_input_file() does on
/// the descriptor it reads from; throws InputError naming the path and the reason.
std::string read_file(const std::string& path, std::uintmax_t max_bytes = kMaxReadBytes);

/// A whole JSON file read through read_file(): InputError `path: not valid JSON (why)` for text
/// that does not parse, with the parser's reason and place but not its internal tag, so every
/// reader of a record names the file the same way.
nlohmann::json read_json_file(const std::string& path, std::uintmax_t max_bytes = kMaxReadBytes);

/// The text of a JSON parser's exception without its "[json.exception.parse_error.101] " tag.
std::string json_error_text(const std::exception& e);

/// Throws InputError naming both paths when two of `paths` hold the same bytes (compared by
/// content, so a copy under another name is caught too): one photo listed twice is one view,
/// not two independent ones, and would shrink the spread it feeds by the square root of the
/// repeats. `option` names the list in the message ("measure's side views").
void refuse_repeated_contents(const std::vector<std::string>& paths, const std::string& option);

/// Why an output is refused.
enum class OutputRefusal {
  kIsInput,        // the same file as an input of the command
  kNotRegular,     // a folder, FIFO, socket, device or symlink stands at the path
  kDuplicate,      // two outputs of one command at one file
  kNotMade,        // an existing file this program did not make (and no --force)
  kEscapesFolder,  // a symlink inside a command's folder leads outside it
};

/// An output refused before anything was written; the message names the path and the reason.
class OutputRefused : public InputError {
 public:
  OutputRefused(OutputRefusal why, const std::string& message) : InputError(message), why_(why) {}
  OutputRefusal why() const { return why_; }

 private:
  OutputRefusal why_;
};

/// Writes `text` to `path` atomically: a temporary file in the same folder, flushed to the disk
/// (fsync) before the rename that publishes it, so a reader, or the machine after a crash, sees
/// the old file or the whole new one. The temporary is removed on failure (a full disk). Throws
/// OutputRefused (kNotRegular) when something other than a regular file is at `path`, and
/// std::runtime_error naming the path when the write fails. Creates missing parent folders.
void write_file_atomic(const std::string& path, const std::string& text);

/// Writes JSON (indented) atomically.
void write_json_atomic(const std::string& path, const nlohmann::json& j);

/// write_file_atomic(), then records `path` in its folder's manifest as made by this program.
void write_made_file(const std::string& path, const std::string& text);

/// Whether `path` is a file this program made: listed in its folder's manifest with the inode,
/// size and modification time it has now.
bool made_by_us(const std::string& path);

/// The manifest's file name, kept in each folder an OutputPlan writes into.
inline constexpr const char* kMadeManifest = ".reposetwin-made.json";

/// Throws OutputRefused (kEscapesFolder) naming the link and where it leads when a symlink
/// anywhere inside `folder` resolves outside it (a dangling one too). A missing folder passes.
void refuse_escaping_links(const std::string& folder);

/// The files one command reads and writes, checked together before anything is written.
class OutputPlan {
 public:
  /// `force`: the command's --force, which allows replacing a file it did not make (never an
  /// input or a non-regular file).
  explicit OutputPlan(bool force = false) : force_(force) {}

  /// A file the command reads. An output that is the same file is refused, even with --force.
  void add_input(const std::string& path);

  /// A file the command will write; `option` names where it came from ("--overlay") in messages.
  void add_output(const std::string& path, const std::string& option = "");

  /// Checks every output; throws OutputRefused naming the first refused path, its option and the
  /// reason (and what to do).
  void check() const;

  /// Writes `text` to `path`, an output of this plan, atomically, and records it as made by this
  /// program (write_made_file). Throws std::logic_error for a path the plan does not hold.
  void write(const std::string& path, const std::string& text) const;

 private:
  struct Output {
    std::filesystem::path path;
    std::string option;
  };
  bool force_;
  std::vector<std::filesystem::path> inputs_;
  std::vector<Output> outputs_;
};

}  // namespace reposetwin::experiments
