// The renderer's realism switches as a scenario declares them (DESIGN.md section 9): one struct,
// GL-free, nested in the Scenario, read by the renderer node, the in-process episode and datagen,
// and the base of unav::renderer::RenderOptions (which adds the engine's own knobs).
#pragma once

#include "unav_common/config.hpp"

namespace unav::scene {

struct RenderSettings {
  bool forward_scatter = true;   ///< range-dependent blur (the paper's F term)
  bool marine_snow = true;       ///< drifting particles lit by the lamps
  bool noise = true;             ///< sensor shot + read noise
  bool lamps = true;             ///< the vehicle's lamps light the scene
  int lamp_scatter_samples = 8;  ///< ray-march steps for lamp in-scattering, 0..256; 0 disables
  bool shadows = true;           ///< shadow maps of the sun and of every lamp
  bool caustics = true;          ///< animated sunlight caustics on the seabed
  bool materials = true;         ///< relief (bump), GGX highlights and sediment of the materials
  bool snell_window = true;      ///< the sky through the surface within the critical angle
  bool auto_exposure = true;     ///< meter the ambient light at the camera depth

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("forward_scatter", &forward_scatter).Doc("range-dependent blur (forward scattering)"));
    a->Visit(Field("marine_snow", &marine_snow).Doc("marine snow particles"));
    a->Visit(Field("noise", &noise).Doc("camera shot and read noise"));
    a->Visit(Field("lamps", &lamps).Doc("the vehicle's lamps light the scene"));
    a->Visit(Field("lamp_scatter_samples", &lamp_scatter_samples).Range(0, 256).Doc("0 = no lamp in-scattering"));
    a->Visit(Field("shadows", &shadows).Doc("shadow maps of the sun and of every lamp"));
    a->Visit(Field("caustics", &caustics).Doc("animated sunlight caustics on the seabed"));
    a->Visit(Field("materials", &materials).Doc("relief (bump), GGX highlights and sediment of the materials"));
    a->Visit(Field("snell_window", &snell_window).Doc("sky and sun glint through Snell's window"));
    a->Visit(Field("auto_exposure", &auto_exposure).Doc("meter the ambient light at the camera depth"));
  }
};

}  // namespace unav::scene
