#include "robot_description_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::physics::RobotDescriptionNode>(argc, argv); }
