// A fixture of the layer check (tests/CMakeLists.txt): pile/ including io/ is the right way.
#pragma once
#include "experiments/io/scene.hpp"
