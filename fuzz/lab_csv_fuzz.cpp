// Fuzz harness: the measured-data CSV reader of the closed loop (experiments/loop/loop_data), as
// `reposetwin loop DATA.csv` reads it, with the scenes and photos its rows may name.
#include "experiments/loop/loop_data.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace reposetwin;
  const std::string path = fuzz::write_input(data, size, "fuzz_data.csv");
  fuzz::expect_clear_refusal("fuzz_data.csv", [&] { (void)experiments::read_lab_csv(path); });
  return 0;
}
