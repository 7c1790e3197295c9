// Python module latentoc._bridge: builds serialized casadi Functions from a serialized pinocchio.Model.
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include "bridge.hpp"

#include <casadi/config.h>
#include <pinocchio/config.hpp>

namespace nb = nanobind;
using latentoc::BridgeModel;

NB_MODULE(_bridge, m) {
  m.doc() = "Pinocchio algorithms on casadi::SX, returned as serialized casadi Functions.";
  m.attr("casadi_version") = CASADI_VERSION_STRING;
  m.attr("pinocchio_version") = PINOCCHIO_VERSION;
  nb::class_<BridgeModel>(m, "BridgeModel")
      .def(nb::init<const std::string&>(), nb::arg("serialized_model"))
      .def_prop_ro("nq", &BridgeModel::nq)
      .def_prop_ro("nv", &BridgeModel::nv)
      .def("rnea", &latentoc::build_rnea)
      .def("com", &latentoc::build_com)
      .def("centroidal_momentum", &latentoc::build_centroidal_momentum)
      .def("centroidal_momentum_rate", &latentoc::build_centroidal_momentum_rate)
      .def("frame_placement", &latentoc::build_frame_placement, nb::arg("frame"))
      .def("frame_velocity", &latentoc::build_frame_velocity, nb::arg("frame"))
      .def("frame_jacobian", &latentoc::build_frame_jacobian, nb::arg("frame"))
      .def("mass_matrix", &latentoc::build_mass_matrix)
      .def("integrate", &latentoc::build_integrate)
      .def("difference", &latentoc::build_difference);
}
