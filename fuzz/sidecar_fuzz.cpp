// Fuzz harness: a render's sidecar JSON (its camera, and the scale vision takes from it), as
// `reposetwin measure` and the loop's photo columns read one next to an image.
#include "camera/camera.hpp"
#include "fuzz/fuzz_support.hpp"
#include "vision/measure.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace reposetwin;
  const std::string path = fuzz::write_input(data, size, "fuzz_view.json");
  fuzz::expect_clear_refusal("fuzz_view.json", [&] { (void)camera::read_sidecar(path); });
  fuzz::expect_clear_refusal("fuzz_view.json", [&] { (void)vision::scale_from_sidecar(path); });
  return 0;
}
