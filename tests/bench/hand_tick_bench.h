// What bench_main.cc needs to know about hand_tick_bench.cc's objects.
#pragma once

#include <string>

namespace telegrasp::sim {

/// True for an object of the generated "unseen" set (tests/bench/unseen_meshes.h).
bool is_unseen_object(const std::string& name);

}  // namespace telegrasp::sim
