#include "drl_planner_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::planning::DrlPlannerNode>(argc, argv); }
