// Fabric presets (with where their figures come from: docs/fabric.md "Presets") and the range check of a fabric.
#include "drape/fabric.hpp"

#include <cmath>
#include <sstream>

#include "drape/errors.hpp"

namespace drape {

const char* material_model_name(MaterialModel model) noexcept {
    return model == MaterialModel::fabric ? "fabric" : "springs";
}

namespace {

// KES-F units to SI (docs/fabric.md "Units").
/// Tensile load at which KES-FB1 reads EMT (standard condition for woven fabrics): 500 gf/cm, in N/m.
constexpr double kes_max_load_n_per_m = 500.0 * 9.80665e-3 / 0.01;
/// Secant tensile stiffness per unit width, N/m, from EMT (% strain at the maximum load).
constexpr double kes_tensile(double emt_percent) { return kes_max_load_n_per_m / (emt_percent / 100.0); }
/// Shear rigidity G, gf/cm/deg -> N/m per radian.
constexpr double kes_shear(double g) { return g * 9.80665e-3 / 0.01 * 180.0 / 3.14159265358979323846; }
/// Bending rigidity B, gf cm^2/cm -> N*m (per unit width).
constexpr double kes_bend(double b) { return b * 9.80665e-5; }

// FAST (SiroFAST, CSIRO) units to SI: bending rigidity is already uN*m and shear rigidity G already N/m (per radian).
/// Secant tensile stiffness per unit width, N/m, from E100 (% extension at 100 gf/cm = 98.07 N/m).
constexpr double fast_tensile(double e100_percent) { return 100.0 * 9.80665e-3 / 0.01 / (e100_percent / 100.0); }

// Wang, O'Brien and Ramamoorthi 2011 (ARCSim data files): the zero-strain row (k0, k1, k2, k3) of a fabric's
// "stretching" table, read as ARCSim does (stiffness = 2 x the file's figures; energy per area
// 1/2 (k0 G00^2 + 2 k1 G00 G11 + k2 G11^2 + k3 G01^2) in the Green strain G, docs/fabric.md "Units").
/// Tensile stiffness along u with the sides free, N/m: k0 - k1^2 / k2.
constexpr double wang_tensile_u(double d0, double d1, double d2) { return 2.0 * (d0 - d1 * d1 / d2); }
/// Tensile stiffness along v with the sides free, N/m: k2 - k1^2 / k0.
constexpr double wang_tensile_v(double d0, double d1, double d2) { return 2.0 * (d2 - d1 * d1 / d0); }
/// Shear stiffness, N/m per radian of shear angle: G01 is half the angle, so G = k3 / 4.
constexpr double wang_shear(double d3) { return 2.0 * d3 / 4.0; }

/// Rayleigh beta, s, that keeps the stiffest mode's damping ratio at `zeta` at spacing h: the explicit bound of a
/// grid is dt ~ h / (2 c) with c = sqrt(stretch / density) the membrane wave speed, and the highest mode (w = 2/dt)
/// gets damping ratio beta w / 2 = beta / dt. zeta = 0.03 at h = 1 cm (the finest default scene, hang N = 100 on 1 m)
/// lowers that bound by about 3% (docs/fabric.md "Damping").
double rayleigh_beta(double density, double stretch, double zeta = 0.03, double h = 0.01) {
    const double c = std::sqrt(stretch / density);
    return zeta * h / (2.0 * c);
}

FabricPreset make(const char* name, double gsm, double stretch_u, double stretch_v, double shear, double bend_u,
                  double bend_v, const char* description, const char* source) {
    FabricPreset p;
    p.fabric.name = name;
    p.fabric.density = static_cast<float>(gsm / 1000.0);
    p.fabric.stretch_u = static_cast<float>(stretch_u);
    p.fabric.stretch_v = static_cast<float>(stretch_v);
    p.fabric.shear = static_cast<float>(shear);
    p.fabric.bend_u = static_cast<float>(bend_u);
    p.fabric.bend_v = static_cast<float>(bend_v);
    p.fabric.damping = static_cast<float>(rayleigh_beta(gsm / 1000.0, std::max(stretch_u, stretch_v)));
    p.description = description;
    p.source = source;
    return p;
}

std::vector<FabricPreset> build_presets() {
    std::vector<FabricPreset> out;
    // Every figure below is listed, converted and sourced in docs/fabric.md "Presets"; "estimate" there marks a
    // figure that is not a measurement of that fabric. denim: KES-F; wool: FAST; jersey: Wang et al. 2011.
    out.push_back(make("silk", 60.0, kes_tensile(8.0), kes_tensile(10.0), kes_shear(0.35), kes_bend(0.025),
                       kes_bend(0.02), "silk, crepe de chine / habotai class, 60 g/m^2",
                       "estimate within the KES-F ranges of silk filament weaves (Matsudaira, Kanazawa Univ. "
                       "repository no. 37-139: silk weaves stretchy, very low shear stiffness at small strain)"));
    out.push_back(make("cotton_shirting", 120.0, kes_tensile(4.0), kes_tensile(6.0), kes_shear(0.9), kes_bend(0.09),
                       kes_bend(0.06), "cotton shirting, plain weave (poplin), 120 g/m^2",
                       "estimate: typical KES-F values of cotton shirtings (EMT 3-8 %, G 0.5-1.5 gf/cm/deg, "
                       "B 0.05-0.12 gf cm^2/cm)"));
    // Wang et al. 2011 "gray-interlock": stretching row 0 = (16.593832, -14.695990, 34.477123, 36.860302); bending
    // at the smallest curvature: 14.267624e-6 (hinges along v, row 2) and 23.191698e-6 (hinges along u, row 0).
    out.push_back(make("jersey", 187.0, wang_tensile_u(16.593832, -14.695990, 34.477123),
                       wang_tensile_v(16.593832, -14.695990, 34.477123), wang_shear(36.860302), 14.267624e-6,
                       23.191698e-6, "cotton/polyester interlock (double jersey) knit, T-shirt fabric, 187 g/m^2",
                       "measured: Wang, O'Brien and Ramamoorthi, 'Data-driven elastic models for cloth', ACM TOG 30(4) "
                       "2011, fabric 'gray-interlock' (60% cotton 40% polyester, T-shirt) as distributed with ARCSim "
                       "(materials/gray-interlock.json): density 0.187 kg/m^2, zero-strain stretching row, bending "
                       "at the smallest curvature taken as N*m (conversion factor uncertain, docs/fabric.md)"));
    out.push_back(make("linen", 180.0, kes_tensile(2.5), kes_tensile(3.5), kes_shear(2.5), kes_bend(0.25),
                       kes_bend(0.18), "linen, plain weave, 180 g/m^2",
                       "estimate: linen is the stiffest of the common apparel wovens in KES-F bending and shear"));
    out.push_back(make("wool", 168.0, fast_tensile(4.60), fast_tensile(5.87), 26.17, 5.56e-6, 5.02e-6,
                       "100% wool, plain weave, 168 g/m^2",
                       "measured with SiroFAST, but an unreviewed student lab report ('Fabric Assurance by Simple "
                       "Testing (F.A.S.T)', posted on bartleby.com and majortests.com): W 168 g/m^2, B 5.56 / 5.02 "
                       "uN*m (warp / weft), E100 4.60 / 5.87 %, G 26.17 N/m (EB5 4.7 %)"));
    out.push_back(make("denim", 270.0, kes_tensile(5.515), kes_tensile(5.515), kes_shear(2.180), kes_bend(0.172),
                       kes_bend(0.172), "lightweight denim, 3/1 twill, 270 g/m^2 (8 oz/yd^2)",
                       "KES-F of denim fabric A in Journal of Textiles 2016, article 4614168 ('Regenerated "
                       "cellulose-based denim fabric for tropical regions'), Table 5: EMT 5.515 %, G 2.180 gf/cm/deg, "
                       "B 0.172 gf cm^2/cm (one value for both directions); areal weight an estimate (the table's weight "
                       "column is not usable as printed)"));
    out.push_back(make("chiffon", 40.0, kes_tensile(6.0), kes_tensile(8.0), kes_shear(0.25), kes_bend(0.008),
                       kes_bend(0.006), "polyester chiffon, sheer plain weave, 40 g/m^2",
                       "estimate: the lightest, most drapeable woven apparel fabrics"));
    out.push_back(make("canvas", 400.0, kes_tensile(1.5), kes_tensile(2.0), kes_shear(5.0), kes_bend(1.5),
                       kes_bend(1.2), "cotton canvas (duck), plain weave, 400 g/m^2",
                       "estimate: a stiff, heavy woven for bags, tents and upholstery"));
    return out;
}

std::string range_text(double lo, double hi, const char* unit) {
    std::ostringstream out;
    out << "[" << lo << ", " << hi << "] " << unit;
    return out.str();
}

} // namespace

const std::vector<FabricPreset>& fabric_presets() {
    static const std::vector<FabricPreset> presets = build_presets();
    return presets;
}

std::optional<Fabric> find_fabric(const std::string& name) {
    for (const FabricPreset& p : fabric_presets())
        if (p.fabric.name == name) return p.fabric;
    return std::nullopt;
}

std::string fabric_preset_names() {
    std::string out;
    for (const FabricPreset& p : fabric_presets()) out += (out.empty() ? "" : ", ") + p.fabric.name;
    return out;
}

void validate_fabric(const Fabric& f, const std::string& what) {
    // Ranges in file units (g/m^2, N/m, micro-N*m, s), wide enough for every real fabric from tulle to canvas.
    struct Field {
        const char* name;
        double value; // in file units
        FabricRange range;
    };
    const Field fields[] = {
        {"density_gsm", double(f.density) * fabric_gsm_per_kg_m2, fabric_range_density_gsm},
        {"stretch_u", double(f.stretch_u), fabric_range_stretch},
        {"stretch_v", double(f.stretch_v), fabric_range_stretch},
        {"shear", double(f.shear), fabric_range_shear},
        {"bend_u_uNm", double(f.bend_u) * fabric_uNm_per_Nm, fabric_range_bend_uNm},
        {"bend_v_uNm", double(f.bend_v) * fabric_uNm_per_Nm, fabric_range_bend_uNm},
        {"damping", double(f.damping), fabric_range_damping},
    };
    for (const Field& fl : fields) {
        // A little slack: a value converted from the file's unit and back may round past the bound.
        const double slack = 1e-6 * std::max(std::fabs(fl.range.lo), std::fabs(fl.range.hi));
        if (!(fl.value >= fl.range.lo - slack && fl.value <= fl.range.hi + slack)) {
            std::ostringstream v;
            v << fl.value;
            throw InvalidInput(what + "." + fl.name + " = " + v.str() + " " + fl.range.unit +
                               " is outside the allowed range " + range_text(fl.range.lo, fl.range.hi, fl.range.unit));
        }
    }
    // The springs' reference damping is damping x a reference stiffness (Rayleigh), at most 1e3 N*s/m (cook_cloth
    // checks it): stretch_u on grids, the mean of the two stretches on meshes. A stiff fabric allows less than the
    // range above (canvas at 0.1 s was refused as "material.structural.damping = 3241 N*s/m", a field no file has).
    // The larger of the two references, so what cook_cloth would refuse on either kind of cloth is refused here, in
    // the file's words (with the smaller one a grid of stretch_u 1e6 N/m and stretch_v 10 at 0.001 s passed here and
    // was refused there as "material.structural.damping = 1000.000061 N*s/m"). The limit itself is allowed: damping
    // in float times the stiffness may round past it by a few parts in 1e8.
    const double stiffest = std::max(double(f.stretch_u), 0.5 * (double(f.stretch_u) + double(f.stretch_v)));
    if (stiffest > 0.0 && double(f.damping) * stiffest > 1e3 * (1.0 + 1e-6)) {
        std::ostringstream v;
        v << what << ".damping = " << double(f.damping) << " s gives springs of this fabric's stretch stiffness (at least "
          << stiffest << " N/m) a damping of " << double(f.damping) * stiffest
          << " N*s/m, above the most a spring takes (1e3 N*s/m): at most " << 1e3 / stiffest << " s for this fabric";
        throw InvalidInput(v.str());
    }
}

} // namespace drape
