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
    // figure that is not a measurement of that fabric.
    out.push_back(make("silk", 60.0, kes_tensile(8.0), kes_tensile(10.0), kes_shear(0.35), kes_bend(0.025),
                       kes_bend(0.02), "silk, crepe de chine / habotai class, 60 g/m^2",
                       "estimate within the KES-F ranges of silk filament weaves (Matsudaira, Kanazawa Univ. "
                       "repository no. 37-139: silk weaves stretchy, very low shear stiffness at small strain)"));
    out.push_back(make("cotton_shirting", 120.0, kes_tensile(4.0), kes_tensile(6.0), kes_shear(0.9), kes_bend(0.09),
                       kes_bend(0.06), "cotton shirting, plain weave (poplin), 120 g/m^2",
                       "estimate: typical KES-F values of cotton shirtings (EMT 3-8 %, G 0.5-1.5 gf/cm/deg, "
                       "B 0.05-0.12 gf cm^2/cm)"));
    out.push_back(make("jersey", 160.0, kes_tensile(30.0), kes_tensile(60.0), kes_shear(0.3), kes_bend(0.035),
                       kes_bend(0.02), "cotton single jersey knit, 160 g/m^2 (u = wales, v = courses)",
                       "estimate: knits stretch 5-10x more than wovens under the same KES-F load; bending "
                       "and shear from the low end of the woven ranges"));
    out.push_back(make("linen", 180.0, kes_tensile(2.5), kes_tensile(3.5), kes_shear(2.5), kes_bend(0.25),
                       kes_bend(0.18), "linen, plain weave, 180 g/m^2",
                       "estimate: linen is the stiffest of the common apparel wovens in KES-F bending and shear"));
    out.push_back(make("wool", 250.0, kes_tensile(4.0), kes_tensile(5.0), kes_shear(0.6), kes_bend(0.10),
                       kes_bend(0.08), "worsted wool suiting, twill, 250 g/m^2",
                       "estimate: KES-F values of men's worsted suitings (EMT ~4 %, G ~0.6 gf/cm/deg, "
                       "B ~0.1 gf cm^2/cm; Kawabata and Niwa's suiting data)"));
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
}

} // namespace drape
