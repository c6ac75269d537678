#include <stdexcept>

#include "apps/reposetwin/commands.hpp"

namespace reposetwin::cli {

void add_run_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "Run a scene file (the embedded quick scene by default)");
  cmd->callback([]() { throw std::runtime_error("run: the engine is not wired yet"); });
}

}  // namespace reposetwin::cli
