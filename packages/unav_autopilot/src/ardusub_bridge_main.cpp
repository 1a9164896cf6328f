#include "ardusub_bridge_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::autopilot::ArduSubBridge>(argc, argv); }
