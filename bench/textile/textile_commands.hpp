// drape_textile's subcommands, one file each (bench/textile/cmd_*.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace drape::textile {

struct Options {
    int threads = 1;
    bool quick = false; ///< coarse spacings only
    bool fine = false;  ///< add the finest (slow) resolution
    bool static_only = false; ///< hang: settle from flat without the swing
    std::vector<std::uint32_t> sizes; ///< hang: grid sizes (default 32, 64, 128)
    std::vector<double> spacings;     ///< cusick: grid spacings, m (default 0.02, 0.01, 0.005)
    double max_time = 0.0;           ///< cusick: settling time limit, s (0: the default, 6 s)
    bool square = false;              ///< cusick: the 30 cm square grid cloth instead of the standard 30 cm circle
    bool square_outline = false;      ///< cusick: the 30 cm square as an outline cloth (the circle's mesh model)
    bool mask_circle = false;         ///< cusick: the 30 cm circle as a mask cloth (grid cells within the circle)
    std::string png_dir;
    std::vector<std::string> fabrics;
    int samples = 1;    ///< cusick: meshes of each specimen (other lattice phases of the same circle), mean DC reported
    int sample = -1;    ///< cusick: only this one of the `samples` meshes (0-based; -1 all), to split an ensemble
    double shear = 0.0; ///< cusick: > 0 replaces each preset's in-plane shear stiffness, N/m (a diagnostic)
    std::vector<std::pair<std::string, double>> set; ///< cusick: Fabric fields replaced (--set FIELD=VALUE)
    bool energies = false; ///< cusick: print each settled specimen's energies (bending, membrane, gravity)
    int skirt = 0;         ///< cusick: > 0: energies of a fixed skirt with this many folds on each mesh, no drop
    bool skirt_smooth = false; ///< cusick --skirt: the skirt's curvature starts from 0 at the rim
    double rim_bend = 1.0; ///< cusick: weight factor of the hinges within 2 cm past the disc's rim (a diagnostic)
    bool clamp = false;    ///< cusick: the specimen clamped between discs (pinned within the disc's radius)
    double stretch_scale = 1.0; ///< cusick: multiplies each preset's stretch_u and stretch_v (a diagnostic)
    double drag = 0.0;  ///< cusick: air drag while the specimen falls and settles, 1/s (0: the default, 2 1/s)
};

int cmd_cantilever(const Options& opt);
int cmd_tension(const Options& opt);
int cmd_cusick(const Options& opt);
int cmd_hang(const Options& opt);
int cmd_verlet(const Options& opt);

} // namespace drape::textile
