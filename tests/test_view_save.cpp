// File > Save scene (app/view_tools.cpp): ViewSession::current_spec() is the scene as the panels have it, so a
// saved file rebuilds the cloth the viewer shows - same size, masses, materials and physics - and, with
// capture_state(), continues from the viewer's state.
#include <gtest/gtest.h>

#include <cstring>

#include "drape/scene.hpp"
#include "drape/scene_write.hpp"
#include "view_session.hpp"

using namespace drape;
using drape::app::ViewSession;

TEST(ViewSave, CurrentSpecHoldsThePanelSettings) {
    ViewSession s(20, 1, std::nullopt);
    s.set_stiffness(SpringKind::structural, 2000.0f);
    s.set_stiffness(SpringKind::bend, 300.0f);
    s.set_damping_ratio(0.2f);
    s.set_gravity({0.5f, -5.0f, 0.0f});
    s.set_air_drag(0.7f);
    const SceneSpec spec = s.current_spec();
    EXPECT_EQ(spec.grid.n, 20u);
    EXPECT_FLOAT_EQ(spec.stiffness, 2000.0f);
    EXPECT_FLOAT_EQ(spec.shear_ratio * spec.stiffness, s.fabric().stiffness[1]);
    EXPECT_FLOAT_EQ(spec.bend_ratio * spec.stiffness, 300.0f);
    EXPECT_FLOAT_EQ(spec.damping_ratio, 0.2f);
    EXPECT_FLOAT_EQ(spec.physics.gravity[0], 0.5f);
    EXPECT_FLOAT_EQ(spec.physics.gravity[1], -5.0f);
    EXPECT_FLOAT_EQ(spec.physics.air_drag, 0.7f);
    EXPECT_FALSE(spec.state.has_value());
    // Written and read back, it builds the viewer's cloth: the same particles, masses and materials.
    const SceneSpec back = parse_scene(scene_to_json(spec), "saved.json");
    const BuiltScene built = build_scene(back);
    const Cloth& shown = s.sim().cloth();
    ASSERT_EQ(built.cloth.particle_count, shown.particle_count);
    EXPECT_NEAR(1e3 / built.cloth.inv_mass[5], s.fabric().node_mass_g, 1e-4 * s.fabric().node_mass_g);
    for (std::size_t k = 0; k < 3; ++k)
        EXPECT_NEAR(built.cloth.material[k].stiffness, shown.material[k].stiffness,
                    1e-4 * shown.material[k].stiffness)
            << spring_kind_name(static_cast<SpringKind>(k));
    EXPECT_FLOAT_EQ(built.params.air_drag, 0.7f);
}

TEST(ViewSave, SavedStateContinuesTheViewersRun) {
    ViewSession s(16, 1, 5);
    for (int f = 0; f < 20; ++f)
        s.advance();
    s.toggle_pin(100); // a user pin is saved too
    const SceneState state = capture_state(s.sim());
    const SceneSpec back = parse_scene(scene_to_json(s.current_spec(), &state), "saved.json");
    ASSERT_TRUE(back.state.has_value());
    const BuiltScene built = build_scene(back);
    ASSERT_EQ(built.initial.x.size(), s.sim().cloth().particle_count);
    EXPECT_EQ(0, std::memcmp(built.initial.y.data(), s.sim().y().data(), built.initial.y.size() * sizeof(float)));
    EXPECT_EQ(built.cloth.inv_mass[100], 0.0f); // pinned
}
