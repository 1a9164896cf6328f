// Python binding of the pipe-following environment core (unav_sim): module unav_gym._core.
// The Gymnasium classes are Python (python/unav_gym/envs.py); this file converts types only.
// Steps release the GIL. unav::ConfigError -> ValueError (message names file, key, value, rule).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "unav_common/crash_report.hpp"
#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_sim/pipe_following_env.hpp"

namespace py = pybind11;
using unav::sim::PipeFollowingConfig;
using unav::sim::PipeFollowingEnv;
using unav::sim::PipeFollowingInfo;
using unav::sim::PipeFollowingStep;
using unav::sim::VectorPipeFollowingEnv;

namespace {

PipeFollowingConfig make_config(const std::string& path, const std::map<std::string, std::string>& overrides) {
  const std::string file = path.empty() ? unav::common::find_resource("config/learning/pipe_following.yaml") : path;
  PipeFollowingConfig c = unav::sim::load_pipe_following_config(file);
  for (const auto& [k, v] : overrides) unav::sim::apply_override(&c, k, v, "make() keyword " + k);
  return c;
}

py::dict to_dict(const PipeFollowingInfo& i) {
  py::dict d;
  d["e_p"] = i.e_p;
  d["e_psi"] = i.e_psi;
  d["lateral"] = i.lateral_m;
  d["arc_length"] = i.arc_length_m;
  d["progress"] = i.progress;
  d["pipe_length"] = i.pipe_length_m;
  d["time"] = i.time_s;
  d["steps"] = i.steps;
  d["pipe_end"] = i.pipe_end;
  d["scene_seed"] = i.scene_seed;
  d["clipped_actions"] = i.clipped_actions;
  d["rejected_actions"] = i.rejected_actions;
  d["position"] = py::make_tuple(i.position_W[0], i.position_W[1], i.position_W[2]);
  d["yaw"] = i.yaw;
  return d;
}

py::array_t<std::uint8_t> image(const std::vector<std::uint8_t>& px, py::ssize_t n, int h, int w) {
  std::vector<py::ssize_t> shape{h, w, 3};
  if (n > 0) shape.insert(shape.begin(), n);
  py::array_t<std::uint8_t> a(shape);
  std::memcpy(a.mutable_data(), px.data(), px.size());
  return a;
}

std::array<double, 2> action_of(py::handle a) {
  const auto arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!arr || arr.size() != 2)
    throw py::value_error("action must have 2 elements (a1 step direction, a2 heading change) in [-1, 1]");
  return {arr.data()[0], arr.data()[1]};
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "UNav-Sim pipe-following environment core (C++); use unav_gym's Gymnasium classes.";
  // A crash in the core (renderer, dynamics threads) prints its native stack before Python's
  // faulthandler prints the Python one.
  unav::common::InstallCrashReport("unav_gym");
  // pybind11 wants void(*)(std::exception_ptr): by value.
  py::register_exception_translator([](std::exception_ptr p) {  // NOLINT(performance-unnecessary-value-param)
    try {
      if (p) std::rethrow_exception(p);
    } catch (const unav::ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  m.def(
      "default_config", [] { return unav::common::find_resource("config/learning/pipe_following.yaml"); },
      "Path of the installed config/learning/pipe_following.yaml.");

  py::class_<PipeFollowingEnv>(m, "PipeFollowingCore")
      .def(py::init([](const std::string& config, const std::map<std::string, std::string>& overrides) {
             return std::make_unique<PipeFollowingEnv>(make_config(config, overrides));
           }),
           py::arg("config") = "", py::arg("overrides") = std::map<std::string, std::string>{})
      .def_property_readonly("obs_shape",
                             [](const PipeFollowingEnv& e) { return py::make_tuple(e.obs_height(), e.obs_width(), 3); })
      .def("set_option", &PipeFollowingEnv::set_option)
      .def("reset",
           [](PipeFollowingEnv& e, std::uint64_t seed) {
             PipeFollowingInfo info;
             std::vector<std::uint8_t> obs;
             {
               py::gil_scoped_release nogil;
               info = e.reset(seed);
               obs = e.observe();
             }
             return py::make_tuple(image(obs, 0, e.obs_height(), e.obs_width()), to_dict(info));
           })
      .def("step",
           [](PipeFollowingEnv& e, py::handle action) {
             const auto a = action_of(action);
             PipeFollowingStep s;
             std::vector<std::uint8_t> obs;
             {
               py::gil_scoped_release nogil;
               s = e.act(a);
               obs = e.observe();
             }
             return py::make_tuple(image(obs, 0, e.obs_height(), e.obs_width()), s.reward, s.terminated, s.truncated,
                                   to_dict(s.info));
           })
      .def("expert_action", [](const PipeFollowingEnv& e) {
        const auto a = e.expert_action();
        return py::make_tuple(a[0], a[1]);
      });

  py::class_<VectorPipeFollowingEnv>(m, "VectorPipeFollowingCore")
      .def(py::init([](int num_envs, const std::string& config, const std::map<std::string, std::string>& overrides,
                       int num_threads) {
             return std::make_unique<VectorPipeFollowingEnv>(make_config(config, overrides), num_envs, num_threads);
           }),
           py::arg("num_envs"), py::arg("config") = "", py::arg("overrides") = std::map<std::string, std::string>{},
           py::arg("num_threads") = 0)
      .def_property_readonly("num_envs", &VectorPipeFollowingEnv::size)
      .def_property_readonly(
          "obs_shape",
          [](VectorPipeFollowingEnv& v) { return py::make_tuple(v.env(0).obs_height(), v.env(0).obs_width(), 3); })
      .def("set_option",
           [](VectorPipeFollowingEnv& v, const std::string& k, const std::string& value) {
             for (int i = 0; i < v.size(); ++i) v.env(i).set_option(k, value);
           })
      .def("reset",
           [](VectorPipeFollowingEnv& v, const std::vector<std::uint64_t>& seeds) {
             if (static_cast<int>(seeds.size()) != v.size())
               throw py::value_error("reset: " + std::to_string(seeds.size()) + " seeds for " +
                                     std::to_string(v.size()) + " environments");
             std::vector<PipeFollowingInfo> infos;
             std::vector<std::uint8_t> obs;
             {
               py::gil_scoped_release nogil;
               infos = v.reset(seeds, &obs);  // on the envs' GL threads
             }
             py::list li;
             for (const auto& i : infos) li.append(to_dict(i));
             return py::make_tuple(image(obs, v.size(), v.env(0).obs_height(), v.env(0).obs_width()), li);
           })
      .def(
          "step",
          [](VectorPipeFollowingEnv& v, py::handle actions, const std::vector<std::optional<std::uint64_t>>& resets) {
            const auto arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(actions);
            if (!arr || arr.ndim() != 2 || arr.shape(0) != v.size() || arr.shape(1) != 2)
              throw py::value_error("actions must have shape (" + std::to_string(v.size()) + ", 2)");
            std::vector<std::array<double, 2>> a(static_cast<std::size_t>(v.size()));
            for (int i = 0; i < v.size(); ++i) a[static_cast<std::size_t>(i)] = {arr.at(i, 0), arr.at(i, 1)};
            std::vector<PipeFollowingStep> steps;
            std::vector<std::uint8_t> obs;
            {
              py::gil_scoped_release nogil;
              steps = v.step(a, &obs, resets);
            }
            const auto n = static_cast<py::ssize_t>(v.size());
            py::array_t<double> rewards(n);
            py::array_t<bool> terminated(n), truncated(n);
            py::list infos;
            for (py::ssize_t i = 0; i < n; ++i) {
              const auto& s = steps[static_cast<std::size_t>(i)];
              rewards.mutable_at(i) = s.reward;
              terminated.mutable_at(i) = s.terminated;
              truncated.mutable_at(i) = s.truncated;
              infos.append(to_dict(s.info));
            }
            return py::make_tuple(image(obs, n, v.env(0).obs_height(), v.env(0).obs_width()), rewards, terminated,
                                  truncated, infos);
          },
          py::arg("actions"), py::arg("resets") = std::vector<std::optional<std::uint64_t>>{})
      .def(
          "reset_some",
          [](VectorPipeFollowingEnv& v, const std::vector<std::optional<std::uint64_t>>& seeds) {
            if (static_cast<int>(seeds.size()) != v.size())
              throw py::value_error("reset_some: " + std::to_string(seeds.size()) + " entries for " +
                                    std::to_string(v.size()) + " environments");
            const int h = v.env(0).obs_height(), w = v.env(0).obs_width();
            std::vector<std::uint8_t> obs;
            std::vector<std::optional<PipeFollowingInfo>> infos;
            {
              py::gil_scoped_release nogil;
              infos = v.reset_some(seeds, &obs);  // on the envs' GL threads
            }
            py::list li;
            for (const auto& i : infos) li.append(i ? py::object(to_dict(*i)) : py::object(py::none()));
            return py::make_tuple(image(obs, v.size(), h, w), li);
          },
          "Resets the envs with a seed (None: untouched); their first observations (others zero).")
      .def("expert_actions", [](VectorPipeFollowingEnv& v) {
        py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{2}});
        for (int i = 0; i < v.size(); ++i) {
          const auto e = v.env(i).expert_action();
          a.mutable_at(i, 0) = e[0];
          a.mutable_at(i, 1) = e[1];
        }
        return a;
      });
}
