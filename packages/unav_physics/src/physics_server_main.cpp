#include "physics_server_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::physics::PhysicsServer>(argc, argv); }
