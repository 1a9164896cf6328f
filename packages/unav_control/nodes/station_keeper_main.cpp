#include "control_nodes.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::control::StationKeeperNode>(argc, argv); }
