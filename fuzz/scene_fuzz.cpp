// Fuzz harness: the scene parser (experiments/io/scene), as `reposetwin run SCENE` reads a file
// (with the PSD files it may name).
#include "experiments/io/scene.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace reposetwin;
  const std::string path = fuzz::write_input(data, size, "fuzz_scene.toml");
  fuzz::expect_clear_refusal("fuzz_scene.toml", [&] {
    (void)experiments::parse_scene_file(path);
  });
  return 0;
}
