// YAML loaders: the shipped files load; bad values name file, key and value.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "unav_control/config.hpp"

namespace unav::control {
namespace {

const std::string kConfig = UNAV_CONFIG_DIR;

TEST(Config, ShippedMpcFile) {
  const MpcConfig c = load_mpc_config(kConfig + "/controllers/mpc.yaml");
  EXPECT_EQ(c.options.horizon_steps, 20);
  EXPECT_DOUBLE_EQ(c.options.dt, 0.05);
  EXPECT_EQ(c.options.control_blocks, 5);
  EXPECT_TRUE(std::filesystem::exists(c.model_vehicle_path));
  EXPECT_EQ(c.model.name, "bluerov2_heavy");
  const WrenchBox box = Allocator(c.model.thrusters).achievable_wrench_box();
  EXPECT_LT((c.options.input_bounds.upper - c.bounds_margin * box.upper).norm(), 1e-9);
  std::string msg;
  EXPECT_TRUE(c.options.IsValid(&msg)) << msg;
}

TEST(Config, ShippedAllocatorFileMatchesPhysicsVehicle) {
  const AllocatorConfig c = load_allocator_config(kConfig + "/controllers/allocator.yaml");
  const Allocator a = make_allocator(c);
  const Allocator ref(physics::load_vehicle(kConfig + "/vehicles/bluerov2_heavy.yaml").thrusters);
  EXPECT_EQ(a.num_thrusters(), 8);
  EXPECT_LT((a.thruster_matrix() - ref.thruster_matrix()).norm(), 1e-12);
  EXPECT_EQ(c.options.mode, AllocationMode::kRedistributed);
}

class TempConfig : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("unav_control_cfg_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_ / "controllers");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& body) {
    const auto p = dir_ / "controllers" / name;
    std::ofstream(p) << body;
    return p.string();
  }
  std::string mpc_error(const std::string& extra) {
    const std::string f = write("mpc.yaml", "mpc_controller:\n  ros__parameters:\n    model_vehicle_config: " + kConfig +
                                                "/vehicles/bluerov2_heavy.yaml\n" + extra);
    try {
      load_mpc_config(f);
    } catch (const physics::ConfigError& e) {
      return e.what();
    }
    return "no error";
  }
  std::filesystem::path dir_;
};

TEST_F(TempConfig, MpcErrorsNameFileKeyValue) {
  std::string e = mpc_error("    horizon_steps: 0\n");
  EXPECT_NE(e.find("mpc.yaml: mpc_controller.ros__parameters.horizon_steps = 0: must be in [1, 500]"), std::string::npos)
      << e;
  e = mpc_error("    position_weights: [1.0, -3.0, 1.0]\n");
  EXPECT_NE(e.find("position_weights[1] = -3.0: must be >= 0"), std::string::npos) << e;
  e = mpc_error("    attitude_weights: [1.0, 1.0]\n");
  EXPECT_NE(e.find("attitude_weights = [1.0, 1.0]: must be a list of 3 numbers (got 2)"), std::string::npos) << e;
  e = mpc_error("    dt: .nan\n");
  EXPECT_NE(e.find("dt = .nan: must be finite"), std::string::npos) << e;
  e = mpc_error("    horizon: 20\n");
  EXPECT_NE(e.find("horizon = 20: unknown key; allowed keys: model_vehicle_config, horizon_steps"), std::string::npos) << e;
  e = mpc_error("    bounds_margin: 1.5\n");
  EXPECT_NE(e.find("bounds_margin = 1.5: must be in (0, 1]"), std::string::npos) << e;
  e = mpc_error("    disturbance_gain: 2.0\n");
  EXPECT_NE(e.find("disturbance_gain = 2.0: must be in [0, 1]"), std::string::npos) << e;
  e = mpc_error("    control_blocks: 25\n");
  EXPECT_NE(e.find("control_blocks = 25: must be in [1, 20]"), std::string::npos) << e;
  e = mpc_error("    horizon_steps: 4\n    control_blocks: 5\n");
  EXPECT_NE(e.find("control_blocks = 5: must be <= horizon_steps (4)"), std::string::npos) << e;
  // Relative model path resolved against the config root (the parent of controllers/).
  const std::string f = write("mpc2.yaml", "model_vehicle_config: vehicles/missing.yaml\n");
  try {
    load_mpc_config(f);
    FAIL();
  } catch (const physics::ConfigError& err) {
    EXPECT_NE(std::string(err.what()).find(": names a file that does not exist"), std::string::npos) << err.what();
    EXPECT_EQ(err.key(), "model_vehicle_config");
    EXPECT_NE(std::string(err.what()).find((dir_ / "vehicles/missing.yaml").string()), std::string::npos) << err.what();
  }
}

TEST_F(TempConfig, AllocatorErrors) {
  const std::string veh = "vehicle_config: " + kConfig + "/vehicles/bluerov2_heavy.yaml\n";
  auto err = [&](const std::string& body) {
    try {
      load_allocator_config(write("allocator.yaml", veh + body));
    } catch (const physics::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(err("mode: magic\n").find("mode = magic: must be one of {pseudo_inverse, redistributed}"),
            std::string::npos);
  EXPECT_NE(err("failed_thrusters: [T9]\n").find("failed_thrusters = T9: names a thruster the vehicle does not have"),
            std::string::npos);
  EXPECT_NE(err("thruster_weights: [1, 2]\n").find("thruster_weights = 2 entries: must be empty or have one entry per "
                                                  "thruster (8)"),
            std::string::npos);
  EXPECT_NE(err("thruster_weights: [1, 1, 1, 0, 1, 1, 1, 1]\n").find("thruster_weights[3] = 0: must be > 0"),
            std::string::npos);
  EXPECT_NE(err("max_redistribution_iterations: 0\n").find("max_redistribution_iterations = 0: must be in [1, 1000]"),
            std::string::npos);
  const AllocatorConfig c = load_allocator_config(write("ok.yaml", veh + "failed_thrusters: [T3]\nmode: pseudo_inverse\n"));
  ASSERT_EQ(c.failed_thrusters, std::vector<int>{2});
  EXPECT_TRUE(make_allocator(c).thruster_failed(2));
}

}  // namespace
}  // namespace unav::control
