// Fuzz harness: an image file measured as a side view and as a top view (vision/), as
// `reposetwin measure` reads a lab photo. The pixel limit is lowered so that a small compressed
// input cannot expand into a frame whose measurement alone outlasts the fuzzer's timeout; the
// limit itself is tested in tests/vision.
#include "fuzz/fuzz_support.hpp"
#include "vision/image.hpp"
#include "vision/measure.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace reposetwin;
  const std::string path = fuzz::write_input(data, size, "fuzz_photo.png");
  vision::ImageLimits limits;
  limits.max_pixels = 4e6;
  fuzz::expect_clear_refusal("fuzz_photo.png", [&] {
    const cv::Mat image = vision::load_image(path, limits);
    fuzz::expect_clear_refusal("fuzz_photo.png",
                               [&] { (void)vision::measure_side(image, {}, {}, path); });
    fuzz::expect_clear_refusal("fuzz_photo.png",
                               [&] { (void)vision::measure_top(image, {}, {}, path); });
  });
  return 0;
}
