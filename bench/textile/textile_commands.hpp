// drape_textile's subcommands, one file each (bench/textile/cmd_*.cpp).
#pragma once

#include <string>
#include <vector>

namespace drape::textile {

struct Options {
    int threads = 1;
    bool quick = false; ///< coarse spacings only
    bool fine = false;  ///< add the finest (slow) resolution
    std::string png_dir;
    std::vector<std::string> fabrics;
};

int cmd_cantilever(const Options& opt);
int cmd_tension(const Options& opt);
int cmd_cusick(const Options& opt);
int cmd_hang(const Options& opt);
int cmd_verlet(const Options& opt);

} // namespace drape::textile
