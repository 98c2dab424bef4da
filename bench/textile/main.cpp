// drape_textile: the fabric model against textile tests and analytic references (issue 7). Each subcommand prints a
// markdown table (pasted into docs/fabric.md "Verification").
//   drape_textile elastica              Peirce's relation against the exact heavy elastica
//   drape_textile cantilever [--quick]  Peirce cantilever (ASTM D1388) at 10, 5 (and 2.5) mm, two fabrics, u and v
//   drape_textile tension               uniaxial tension, u and v, three spacings
//   drape_textile cusick [--png DIR]    Cusick drape test (ISO 9073-9 geometry) per fabric, three resolutions: the
//                                       standard 30 cm circle (outline cloth), or with --square a 30 cm square grid
//   drape_textile hang                  hang scene convergence, N = 32, 64, 128 [256]
//   drape_textile verlet                Verlet against symplectic Euler at rest, N = 32
// Options: --threads T (default 1) worker threads; --fabric NAME (repeatable) presets; --quick coarse only; --fine
// adds the finest resolution; --png DIR (cusick) top views; --n N (repeatable, hang) grid sizes; --static (hang) the
// settled shape only, no swing; --spacing H (repeatable, cusick) grid spacings in m; --square-outline (cusick) the
// 30 cm square as an outline cloth (the circle's mesh model); --mask-circle (cusick) the 30 cm circle as a mask cloth
// (the cells of a u-v grid within it: no cut triangles, a staircase edge); --square (cusick) the square
// grid specimen instead of the circle; --max-time S (cusick) settling time limit (default 6 s); --shear G (cusick)
// replaces each fabric's in-plane shear stiffness by G N/m (G = stretch / 2 makes a woven's edge modulus the same in
// every direction: a diagnostic of the weave-aligned edge springs); --samples K (cusick, circle) K meshes of each
// specimen (the circle turned, or moved off the cell lattice, by k / K of a step), with the mean DC and its spread;
// --sample I (cusick) only mesh I (0-based) of the K, so that one ensemble can run in several processes;
// --set FIELD=VALUE (cusick, repeatable) sets one Fabric field of every fabric, in the struct's units (a diagnostic:
// density kg/m^2, stretch_u, stretch_v, shear N/m, bend_u, bend_v N*m, damping s; checked by the fabric's own ranges);
// --skirt N (cusick, circle) prints the energies of one fixed analytic skirt with N folds on each mesh instead of
// dropping it (does the discrete model make a coarse skirt cheaper?), --skirt-smooth with its curvature starting
// from 0 at the rim; --rim-bend F (cusick) multiplies the weight of the hinges within 2 cm past the disc's rim by F
// (a diagnostic of the coarse meshes' cheap bend there); --clamp (cusick) clamps the specimen between discs as the standard's tester does (the particles within the disc's
// radius pinned where they start) instead of resting it on the disc; --energies (cusick) prints each settled specimen's energies (bending, with its in-plane part; membrane by
// direction and sign of strain; m g y); --stretch-scale F (cusick) multiplies each fabric's stretch stiffness (u and v) by F (a diagnostic: it moves the
// fabric's stretching-bending length (B / E)^(1/2) and nothing else); --drag D (cusick) the air drag while the specimen falls and settles, 1/s (default 2; higher lowers it more slowly).
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "drape/errors.hpp"
#include "drape/workers.hpp"
#include "elastica.hpp"
#include "harness.hpp"
#include "textile_commands.hpp"

using namespace drape;
using namespace drape::textile;

namespace {

constexpr double pi = 3.14159265358979323846;

int cmd_elastica() {
    std::printf("Peirce's relation c = l (cos(theta/2) / (8 tan theta))^(1/3) against the exact heavy elastica "
                "(l = 1, RK4 4000 steps, shooting)\n\n");
    std::printf("| l/c | chord angle theta (deg) | c Peirce / c | tip deflection / l | small-deflection (l/c)^3/8 |\n");
    std::printf("|---:|---:|---:|---:|---:|\n");
    for (double lam : {0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 7.0, 10.0}) {
        const ElasticaShape e = solve_elastica(1.0, 1.0 / lam);
        const double th = e.chord_angle();
        std::printf("| %.2f | %.3f | %.4f | %.6f | %.6f |\n", lam, th * 180.0 / pi,
                    peirce_bending_length(1.0, th) * lam, -e.tip_y(), std::pow(lam, 3) / 8.0);
    }
    const double l415 = 1.0 / elastica_bending_length(1.0, 41.5 * pi / 180.0);
    std::printf("\nASTM D1388's 41.5 deg: exact l/c = %.5f (Peirce's relation gives l/c = %.5f)\n", l415,
                1.0 / peirce_bending_length(1.0, 41.5 * pi / 180.0));
    return 0;
}

/// A number option's value: the whole text read as a number in [lo, hi], else the message (naming `name`, the range
/// and `unit`) and false.
bool ranged_number(const char* text, const char* name, double lo, double hi, const char* unit, double& out) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !(v >= lo && v <= hi)) {
        std::fprintf(stderr, "drape_textile: %s must be in [%g, %g]%s\n", name, lo, hi, unit);
        return false;
    }
    out = v;
    return true;
}

/// ranged_number for a whole number (a count or an index).
bool ranged_whole_number(const char* text, const char* name, double lo, double hi, const char* unit, int& out) {
    double v = 0.0;
    if (!ranged_number(text, name, lo, hi, unit, v)) return false;
    if (v != std::floor(v)) {
        std::fprintf(stderr, "drape_textile: %s must be a whole number\n", name);
        return false;
    }
    out = static_cast<int>(v);
    return true;
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: drape_textile elastica|cantilever|tension|cusick|hang|verlet [options]\n");
        return 2;
    }
    const std::string cmd = argv[1];
    Options opt;
    for (int a = 2; a < argc; ++a) {
        const std::string s = argv[a];
        if (s == "--threads" && a + 1 < argc) opt.threads = std::atoi(argv[++a]);
        else if (s == "--quick") opt.quick = true;
        else if (s == "--fine") opt.fine = true;
        else if (s == "--png" && a + 1 < argc) opt.png_dir = argv[++a];
        else if (s == "--static") opt.static_only = true;
        else if (s == "--square") opt.square = true;
        else if (s == "--square-outline") opt.square_outline = true;
        else if (s == "--mask-circle") opt.mask_circle = true;
        else if (s == "--energies") opt.energies = true;
        else if (s == "--clamp") opt.clamp = true;
        else if (s == "--skirt-smooth") opt.skirt_smooth = true;
        else if (s == "--rim-bend" && a + 1 < argc) {
            if (!ranged_number(argv[++a], "--rim-bend", 0.1, 10.0, "", opt.rim_bend)) return 2;
        }
        else if (s == "--skirt" && a + 1 < argc) {
            if (!ranged_whole_number(argv[++a], "--skirt", 1.0, 64.0, " (a fold count)", opt.skirt)) return 2;
        }
        else if (s == "--max-time" && a + 1 < argc) {
            if (!ranged_number(argv[++a], "--max-time", 1e-3, 600.0, " s", opt.max_time)) return 2;
        }
        else if (s == "--samples" && a + 1 < argc) {
            if (!ranged_whole_number(argv[++a], "--samples", 1.0, 64.0, "", opt.samples)) return 2;
        }
        else if (s == "--sample" && a + 1 < argc) {
            if (!ranged_whole_number(argv[++a], "--sample", 0.0, 63.0, " (0-based, below --samples)", opt.sample))
                return 2;
        }
        else if (s == "--shear" && a + 1 < argc) {
            if (!ranged_number(argv[++a], "--shear", 0.01, 1e6, " N/m", opt.shear)) return 2;
        }
        else if (s == "--stretch-scale" && a + 1 < argc) {
            if (!ranged_number(argv[++a], "--stretch-scale", 1e-3, 1e3, "", opt.stretch_scale)) return 2;
        }
        else if (s == "--set" && a + 1 < argc) {
            const std::string kv = argv[++a];
            const std::size_t eq = kv.find('=');
            const std::string key = kv.substr(0, eq);
            double value = -1.0;
            if (eq != std::string::npos && eq + 1 < kv.size()) {
                char* end = nullptr;
                value = std::strtod(kv.c_str() + eq + 1, &end);
                if (*end != '\0') value = -1.0; // not a number to the end
            }
            static const char* keys[] = {"density", "stretch_u", "stretch_v", "shear", "bend_u", "bend_v", "damping"};
            bool known = false;
            for (const char* k : keys) known = known || key == k;
            if (!known || !(value >= 0.0 && value <= 1e6)) {
                std::fprintf(stderr, "drape_textile: --set needs FIELD=VALUE, FIELD one of density (kg/m^2), stretch_u, "
                                     "stretch_v, shear (N/m), bend_u, bend_v (N*m), damping (s); VALUE in [0, 1e6]\n");
                return 2;
            }
            opt.set.emplace_back(key, value);
        }
        else if (s == "--drag" && a + 1 < argc) {
            if (!ranged_number(argv[++a], "--drag", 0.1, 100.0, " 1/s", opt.drag)) return 2;
        }
        else if (s == "--spacing" && a + 1 < argc) opt.spacings.push_back(std::atof(argv[++a]));
        else if (s == "--n" && a + 1 < argc) opt.sizes.push_back(static_cast<std::uint32_t>(std::atoi(argv[++a])));
        else if (s == "--fabric" && a + 1 < argc) opt.fabrics.push_back(argv[++a]);
        else {
            std::fprintf(stderr, "drape_textile: unknown option %s\n", s.c_str());
            return 2;
        }
    }
    if (int(opt.square) + int(opt.square_outline) + int(opt.mask_circle) > 1) {
        std::fprintf(stderr, "drape_textile: --square (a grid cloth), --square-outline (an outline cloth) and "
                             "--mask-circle (a mask cloth) exclude each other\n");
        return 2;
    }
    if (opt.square && (opt.energies || opt.rim_bend != 1.0)) {
        std::fprintf(stderr, "drape_textile: --energies and --rim-bend take hinge (triangle-mesh) bending: the circle "
                             "or --square-outline, not the --square grid cloth\n");
        return 2;
    }
    if (opt.skirt > 0 && (opt.square || opt.square_outline || opt.mask_circle || opt.clamp || opt.energies ||
                          opt.rim_bend != 1.0 || opt.samples < 1)) {
        std::fprintf(stderr, "drape_textile: --skirt measures the outline circle without dropping it: it takes --fabric, "
                             "--spacing, --samples and the fabric overrides (--set, --shear, --stretch-scale), not "
                             "--square, --square-outline, --mask-circle, --clamp, --energies or --rim-bend\n");
        return 2;
    }
    if (opt.samples > 1 && (opt.square || opt.square_outline)) {
        std::fprintf(stderr, "drape_textile: --samples takes the circle (outline or --mask-circle): a square has one "
                             "mesh on the weave's grid\n");
        return 2;
    }
    if (opt.sample >= opt.samples) {
        std::fprintf(stderr, "drape_textile: --sample %d names no mesh: --samples %d gives meshes 0 to %d\n", opt.sample,
                     opt.samples, opt.samples - 1);
        return 2;
    }
    if (cmd == "elastica") return cmd_elastica();
    Workers workers(opt.threads);
    return workers.run([&]() -> int {
        try {
            if (cmd == "cantilever") return cmd_cantilever(opt);
            if (cmd == "tension") return cmd_tension(opt);
            if (cmd == "cusick") return cmd_cusick(opt);
            if (cmd == "hang") return cmd_hang(opt);
            if (cmd == "verlet") return cmd_verlet(opt);
        } catch (const InvalidInput& e) { // a fabric made invalid by --set or --shear
            std::fprintf(stderr, "drape_textile: %s\n", e.what());
            return 2;
        }
        std::fprintf(stderr, "drape_textile: unknown command %s\n", cmd.c_str());
        return 2;
    });
}
