// Owning handles of a MuJoCo model and its data, and loading an MJCF file with MuJoCo's
// error message in the exception. No units or frames of its own (MuJoCo's: SI, world).
#pragma once

#include <mujoco/mujoco.h>

#include <memory>
#include <stdexcept>
#include <string>

namespace inhand::mujoco_demo {

struct ModelDeleter {
  void operator()(mjModel* m) const noexcept { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const noexcept { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

/// Compiles an MJCF file; throws std::runtime_error with MuJoCo's message on failure.
inline ModelPtr load_model(const std::string& path) {
  char error[1000] = "";
  ModelPtr m(mj_loadXML(path.c_str(), nullptr, error, sizeof(error)));
  if (!m) throw std::runtime_error("mujoco: cannot load " + path + ": " + error);
  return m;
}

/// Fresh data for a model, at its reference configuration qpos0.
inline DataPtr make_data(const mjModel* m) {
  DataPtr d(mj_makeData(m));
  if (!d) throw std::runtime_error("mujoco: mj_makeData failed");
  return d;
}

/// Where the project's MJCF models are (set by the build: INHAND_MODELS_DIR).
inline std::string model_path(const std::string& file) {
#ifdef INHAND_MODELS_DIR
  return std::string(INHAND_MODELS_DIR) + "/" + file;
#else
  return "models/" + file;
#endif
}

}  // namespace inhand::mujoco_demo
