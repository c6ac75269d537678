// A fixture of the layer check (tests/CMakeLists.txt): io/ including pile/ is the wrong way.
#pragma once
#include "experiments/io/scene.hpp"
#include "experiments/pile/pile_run.hpp"
