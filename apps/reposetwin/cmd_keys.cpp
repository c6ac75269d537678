// `reposetwin keys`: every scene key with its type, default, unit and meaning.
#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "experiments/io/psd_file.hpp"
#include "experiments/io/scene_keys.hpp"

namespace reposetwin::cli {

void add_keys_command(CLI::App& app) {
  auto markdown = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand("keys", "List every scene key: type, default, unit, meaning");
  cmd->add_flag("--markdown", *markdown, "As the Markdown page docs/scene.md");
  cmd->callback([markdown]() {
    if (*markdown) {
      std::cout << experiments::scene_keys_markdown();
      return;
    }
    for (const experiments::SceneKey& k : experiments::scene_keys())
      std::cout << k.key << "  (" << k.type << ", default " << k.default_text
                << (k.unit == "-" ? "" : ", " + k.unit) << ")\n    " << k.meaning << "\n";
    std::cout << "\nPaths: " << experiments::kRelativePathRule << "\n";
  });
}

}  // namespace reposetwin::cli
