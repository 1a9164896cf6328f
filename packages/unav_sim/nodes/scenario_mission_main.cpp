#include "scenario_mission_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::sim::ScenarioMissionNode>(argc, argv); }
