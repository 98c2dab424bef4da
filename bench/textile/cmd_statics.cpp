// drape_textile cantilever / tension: the static textile tests (Peirce cantilever, uniaxial tension).
#include <cmath>
#include <cstdio>

#include "elastica.hpp"
#include "harness.hpp"
#include "textile_commands.hpp"

namespace drape::textile {

namespace {
constexpr double pi = 3.14159265358979323846;
std::vector<std::string> fabrics_or(const Options& opt, std::vector<std::string> dflt) {
    return opt.fabrics.empty() ? dflt : opt.fabrics;
}
} // namespace

int cmd_cantilever(const Options& opt) {
    std::printf("Peirce cantilever (ASTM D1388): square strip, 2 rows held, clamp line at the middle of the held "
                "segment, overhang l = (m + 1/2) h nearest to ASTM's 41.5 deg (l = 2.0 c); c_in = (B/(w g))^(1/3); "
                "c from the settled tip angle by Peirce's relation and by the exact elastica; 'last row': the "
                "elastica's c with the clamp taken at the last held row (l = m h); shape = max node distance from "
                "the elastica / l\n\n");
    std::printf("| fabric | dir | h (mm) | N | l (mm) | c_in (mm) | theta (deg) | theta elastica (deg) | c Peirce (mm) "
                "| err | c elastica (mm) | err | last row err | shape | sim s | steps | wall s |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const double lambda415 = 1.0 / elastica_bending_length(1.0, 41.5 * pi / 180.0);
    std::vector<double> spacings = opt.quick ? std::vector<double>{0.01, 0.005} : std::vector<double>{0.01, 0.005, 0.0025};
    int bad = 0;
    for (const std::string& name : fabrics_or(opt, {"cotton_shirting", "denim"}))
        for (bool along_v : {false, true})
            for (double h : spacings) {
                CantileverCase c;
                c.fabric = textile_fabric(name);
                const double cin = bending_length(along_v ? c.fabric.bend_v : c.fabric.bend_u, c.fabric.density);
                c.overhang = lambda415 * cin;
                c.spacing = h;
                c.along_v = along_v;
                const CantileverResult r = run_cantilever(c);
                const double e1 = r.c_peirce / r.c_input - 1.0, e2 = r.c_elastica / r.c_input - 1.0;
                if (std::fabs(e1) > 0.05 || !r.settle.settled) ++bad;
                std::printf("| %s | %s | %.1f | %u | %.2f | %.2f | %.2f | %.2f | %.2f | %+.1f%% | %.2f | %+.1f%% | "
                            "%+.1f%% | %.4f | %.2f%s | %zu | %.1f |\n",
                            name.c_str(), along_v ? "v" : "u", h * 1e3, r.n, r.overhang * 1e3, r.c_input * 1e3,
                            r.theta * 180.0 / pi, r.theta_reference * 180.0 / pi, r.c_peirce * 1e3, e1 * 100.0,
                            r.c_elastica * 1e3, e2 * 100.0, (r.c_last_row / r.c_input - 1.0) * 100.0,
                            r.shape_error, r.settle.sim_time,
                            r.settle.settled ? "" : " (not settled)", r.settle.steps, r.settle.wall);
                std::fflush(stdout);
            }
    std::printf("\n%d case(s) outside 5%% (Peirce) or not settled\n", bad);
    return 0;
}

int cmd_tension(const Options& opt) {
    std::printf("Uniaxial tension: square strip, one row held, a uniform end load T = 1%% of the stiffness per unit "
                "width on the opposite row; expected strain (T + own weight along the load) / stiffness; measured = "
                "mean displacement of the loaded row / length\n\n");
    std::printf("| fabric | dir | side (cm) | h (mm) | N | T (N/m) | expected strain | measured | error | lateral strain "
                "| sim s | wall s |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    int bad = 0;
    for (const std::string& name : fabrics_or(opt, {"cotton_shirting", "denim"}))
        for (bool along_v : {false, true})
            for (double h : {0.01, 0.005, 0.0025}) {
                TensionCase c;
                c.fabric = textile_fabric(name);
                c.length = 0.1;
                c.spacing = h;
                c.along_v = along_v;
                const TensionResult r = run_tension(c);
                const double err = r.measured_strain / r.expected_strain - 1.0;
                if (std::fabs(err) > 0.01 || !r.settle.settled) ++bad;
                std::printf("| %s | %s | %.0f | %.1f | %u | %.1f | %.5f | %.5f | %+.2f%% | %+.5f | %.2f%s | %.1f |\n",
                            name.c_str(), along_v ? "v" : "u", c.length * 100.0, h * 1e3, r.n, r.tension,
                            r.expected_strain, r.measured_strain, err * 100.0, r.lateral_strain, r.settle.sim_time,
                            r.settle.settled ? "" : " (not settled)", r.settle.wall);
                std::fprintf(stderr, "  final max speed %.3g m/s\n", r.settle.max_speed);
                std::fflush(stdout);
            }
    std::printf("\n%d case(s) outside 1%% or not settled\n", bad);
    return 0;
}

} // namespace drape::textile
