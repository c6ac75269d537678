#include "experiments/io/files.hpp"

#include "experiments/io/hash.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace reposetwin::experiments {

namespace fs = std::filesystem;

namespace {

// What stands at a path that is not a regular file, as a message's reason; "" for a regular
// file.
std::string not_regular(mode_t mode) {
  if (S_ISREG(mode)) return "";
  if (S_ISDIR(mode)) return "is a directory, not a file";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISCHR(mode)) return "is a character device, not a regular file";
  if (S_ISBLK(mode)) return "is a block device, not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  if (S_ISLNK(mode)) return "is a symbolic link, not a regular file";
  return "is not a regular file";
}

std::string errno_text(int e) { return std::strerror(e); }

// The checks of an input on its stat record.
void check_input_stat(const std::string& path, const struct stat& st, std::uintmax_t max_bytes) {
  if (const std::string why = not_regular(st.st_mode); !why.empty())
    throw InputError(path + ": " + why + "; give a regular file");
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes)
    throw InputError(path + ": is " + std::to_string(st.st_size) + " bytes, above the " +
                     std::to_string(max_bytes) + " this file may have");
}

// Writes all of `text` to `fd` and flushes it to the disk; false on any failure.
bool write_all_and_sync(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return ::fsync(fd) == 0;
}

// Makes a rename in `dir` durable: without it a crash can leave the old name after the new
// file's data reached the disk.
void sync_folder(const fs::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// What stands at `p` without following a final symlink; false when nothing does.
bool lstat_at(const fs::path& p, struct stat& st) { return ::lstat(p.c_str(), &st) == 0; }

// A file's identity and state as the manifest records it.
nlohmann::json identity(const struct stat& st) {
  return {{"inode", static_cast<std::uint64_t>(st.st_ino)},
          {"size", static_cast<std::int64_t>(st.st_size)},
          {"mtime_ns", static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 +
                           static_cast<std::int64_t>(st.st_mtim.tv_nsec)}};
}

fs::path manifest_of(const fs::path& file) { return file.parent_path() / kMadeManifest; }

// The manifest of `folder_manifest` as read; an unreadable one (absent, edited by hand, from a
// crash) is an empty one: every file in it then counts as the user's, the safe direction.
nlohmann::json read_manifest(const fs::path& manifest) {
  try {
    std::error_code ec;
    if (!fs::is_regular_file(manifest, ec)) return nlohmann::json::object();
    nlohmann::json j = nlohmann::json::parse(read_file(manifest.string(), 64u << 20));
    if (j.is_object() && j.contains("files") && j["files"].is_object()) return j["files"];
  } catch (const std::exception&) {
  }
  return nlohmann::json::object();
}

// Whether `a` lies inside folder `root` (both absolute and normal).
bool is_within(const fs::path& a, const fs::path& root) {
  const auto [r, x] = std::mismatch(root.begin(), root.end(), a.begin(), a.end());
  return r == root.end() || (std::next(r) == root.end() && r->empty());
}

std::string named(const fs::path& p, const std::string& option) {
  return option.empty() ? p.string() : option + " " + p.string();
}

}  // namespace

void check_input_file(const std::string& path, std::uintmax_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int e = errno;
    if (e == ENOENT) throw InputError(path + ": does not exist");
    throw InputError(path + ": cannot be read (" + errno_text(e) + ")");
  }
  check_input_stat(path, st, max_bytes);
}

std::string read_file(const std::string& path, std::uintmax_t max_bytes) {
  // Checked by name first (opening some devices has effects), then again on the descriptor: a
  // FIFO put in its place since opens at once with O_NONBLOCK, and is refused by fstat.
  check_input_file(path, max_bytes);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(path + ": cannot open (" + errno_text(errno) + ")");
  struct FdClose {
    int fd;
    ~FdClose() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw InputError(path + ": cannot open (" + errno_text(errno) + ")");
  check_input_stat(path, st, max_bytes);
  std::string text(static_cast<std::size_t>(st.st_size), '\0');
  std::size_t done = 0;
  while (true) {
    if (done == text.size()) {
      // One byte more than the size it had: a file that grew is not read half.
      char extra;
      const ssize_t n = ::read(fd, &extra, 1);
      if (n < 0 && errno == EINTR) continue;
      if (n > 0) throw InputError(path + ": grew while it was read");
      break;
    }
    const ssize_t n = ::read(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(path + ": cannot read (" + errno_text(errno) + ")");
    if (n == 0) break;  // shrank while it was read: what is there
    done += static_cast<std::size_t>(n);
  }
  text.resize(done);
  return text;
}

std::string json_error_text(const std::exception& e) {
  std::string why = e.what();
  const std::size_t tag = why.find("] ");
  if (why.rfind("[json.", 0) == 0 && tag != std::string::npos) why.erase(0, tag + 2);
  return why;
}

nlohmann::json read_json_file(const std::string& path, std::uintmax_t max_bytes) {
  const std::string text = read_file(path, max_bytes);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not valid JSON (" + json_error_text(e) + ")");
  }
}

void refuse_repeated_contents(const std::vector<std::string>& paths, const std::string& option) {
  std::vector<std::pair<std::string, std::string>> seen;  // content hash, path
  for (const std::string& p : paths) {
    std::string text;
    try {
      text = read_file(p);
    } catch (const InputError& e) {  // a missing photo: named with the list it is in
      throw InputError(option + ": " + e.what());
    }
    const std::string hash = fnv1a_hex(text) + ":" + std::to_string(text.size());
    for (const auto& [h, first] : seen)
      if (h == hash && read_file(first) == text)
        throw InputError(option + ": " + p + " is the same image as " + first +
                         " (identical bytes); each view must be its own photograph");
    seen.emplace_back(hash, p);
  }
}

void write_file_atomic(const std::string& path, const std::string& text) {
  const fs::path target(path);
  std::error_code ec;
  struct stat st {};
  if (lstat_at(target, st)) {
    if (const std::string why = not_regular(st.st_mode); !why.empty())
      throw OutputRefused(OutputRefusal::kNotRegular,
                          path + ": " + why + "; an output replaces only a regular file");
  }
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  const fs::path tmp =
      target.parent_path() / (target.filename().string() + ".tmp." + std::to_string(::getpid()));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    throw std::runtime_error(path + ": cannot open for writing (" + errno_text(errno) + ")");
  const bool written = write_all_and_sync(fd, text);
  const int saved = errno;
  ::close(fd);
  if (!written) {
    fs::remove(tmp, ec);  // a full disk must not leave the temporary behind
    throw std::runtime_error(path + ": write failed (" + errno_text(saved) + ")");
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string why = ec.message();  // "Is a directory", "Permission denied", ...
    fs::remove(tmp, ec);
    throw std::runtime_error(path + ": cannot move the finished file into place (" + why + ")");
  }
  sync_folder(target.parent_path());
}

void write_json_atomic(const std::string& path, const nlohmann::json& j) {
  // A file name on Linux is any bytes and JSON text is UTF-8: a name that is not UTF-8 is
  // written with U+FFFD in place of its stray bytes rather than failing the write.
  write_file_atomic(path, j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

void write_made_file(const std::string& path, const std::string& text) {
  write_file_atomic(path, text);
  const fs::path file(path);
  struct stat st {};
  if (!lstat_at(file, st)) return;
  const fs::path manifest = manifest_of(file);
  nlohmann::json files = read_manifest(manifest);
  // Entries whose file is gone or changed are dropped, so the manifest stays the folder's size.
  for (auto it = files.begin(); it != files.end();) {
    struct stat other {};
    const bool same =
        lstat_at(file.parent_path() / it.key(), other) && identity(other) == it.value();
    it = same ? std::next(it) : files.erase(it);
  }
  files[file.filename().string()] = identity(st);
  write_file_atomic(manifest.string(),
                    nlohmann::json{{"about",
                                    "files reposetwin wrote in this folder (name: inode, "
                                    "size, modification time); a listed file may be "
                                    "replaced by reposetwin, any other is the user's"},
                                   {"files", files}}
                            .dump(2, ' ', false, nlohmann::json::error_handler_t::replace) +
                        "\n");
}

bool made_by_us(const std::string& path) {
  const fs::path file(path);
  struct stat st {};
  if (!lstat_at(file, st) || !S_ISREG(st.st_mode)) return false;
  const nlohmann::json files = read_manifest(manifest_of(file));
  const auto it = files.find(file.filename().string());
  return it != files.end() && *it == identity(st);
}

void refuse_escaping_links(const std::string& folder) {
  std::error_code ec;
  const fs::path root = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  if (ec || !fs::is_directory(root, ec)) return;
  // The iterator does not follow a symlink to a folder, so every link is seen where it stands
  // and nothing outside is walked.
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    if (!it->is_symlink(ec)) continue;
    // Resolved from the link's own text, so a dangling link is judged by where it would lead.
    std::error_code rec;
    const fs::path written = fs::read_symlink(it->path(), rec);
    fs::path target = written.is_relative() ? it->path().parent_path() / written : written;
    target = fs::weakly_canonical(target, rec);
    if (!rec && is_within(target, root)) continue;
    const std::string to = rec ? written.string() : target.string();
    const fs::path shown = fs::path(folder) / it->path().lexically_relative(root);
    throw OutputRefused(OutputRefusal::kEscapesFolder,
                        shown.string() + ": is a symbolic link leading outside " + folder +
                            " (to " + to +
                            "); a command writes only inside its own folder: replace the link "
                            "by a folder or a file of its own");
  }
}

void OutputPlan::add_input(const std::string& path) { inputs_.emplace_back(path); }

void OutputPlan::add_output(const std::string& path, const std::string& option) {
  outputs_.push_back({fs::path(path), option});
}

void OutputPlan::check() const {
  std::error_code ec;
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    const Output& o = outputs_[i];
    const std::string name = named(o.path, o.option);
    struct stat st {};
    const bool exists = lstat_at(o.path, st);
    // An input reached by another name (a symlink or a hard link to it, "./in.png") is the same
    // file: compared by device and inode, following links on both sides.
    for (const fs::path& in : inputs_)
      if (fs::equivalent(in, o.path, ec) && !ec)
        throw OutputRefused(OutputRefusal::kIsInput,
                            name + ": is the input " + in.string() +
                                "; an output never replaces an input: give another path");
    if (exists) {
      if (const std::string why = not_regular(st.st_mode); !why.empty())
        throw OutputRefused(OutputRefusal::kNotRegular,
                            name + ": " + why + "; an output replaces only a regular file");
    } else {
      // Its folder exists or can be made: a path under a regular file ("notes.txt/x.png") is
      // refused now, not after the outputs before it were written.
      fs::path up = fs::absolute(o.path, ec).lexically_normal().parent_path();
      while (!up.empty() && !fs::exists(up, ec) && up != up.parent_path()) up = up.parent_path();
      if (!fs::is_directory(up, ec))
        throw OutputRefused(OutputRefusal::kNotRegular,
                            name + ": cannot be written: " + up.string() +
                                " is not a folder; give a path in a folder");
    }
    // Two outputs at one file: by name before either exists, by inode once one does.
    const fs::path a = fs::weakly_canonical(fs::absolute(o.path, ec), ec);
    for (std::size_t k = 0; k < i; ++k) {
      std::error_code kec;
      const fs::path b = fs::weakly_canonical(fs::absolute(outputs_[k].path, kec), kec);
      if (a == b || (fs::equivalent(o.path, outputs_[k].path, kec) && !kec))
        throw OutputRefused(OutputRefusal::kDuplicate,
                            name + ": is also " + named(outputs_[k].path, outputs_[k].option) +
                                "; two outputs of one command cannot share a file");
    }
    if (exists && !force_ && !made_by_us(o.path.string()))
      throw OutputRefused(OutputRefusal::kNotMade,
                          name +
                              ": a file is already there that reposetwin did not write as a "
                              "replaceable output (yours, or a run's result); pass --force to "
                              "replace it, or give another path");
  }
}

void OutputPlan::write(const std::string& path, const std::string& text) const {
  const auto it = std::find_if(outputs_.begin(), outputs_.end(),
                               [&](const Output& o) { return o.path == fs::path(path); });
  if (it == outputs_.end())
    throw std::logic_error("OutputPlan::write: " + path + " is not an output of the plan");
  write_made_file(path, text);
}

}  // namespace reposetwin::experiments
