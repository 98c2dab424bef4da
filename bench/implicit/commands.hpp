// drape_implicit's subcommands, one file each (bench/implicit/cmd_*.cpp).
#pragma once

#include "common.hpp"

namespace drape::implicit_bench {

int cmd_realtime(const Options& opt);
int cmd_convergence(const Options& opt);
int cmd_rest(const Options& opt);
/// Runs its own worker arenas (1 thread and opt.threads).
int cmd_throughput(const Options& opt);

} // namespace drape::implicit_bench
