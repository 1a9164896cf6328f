// Umbrella header of the node runtime.
#pragma once
#include "unav_runtime/context.hpp"
#include "unav_runtime/names.hpp"
#include "unav_runtime/node.hpp"
#include "unav_runtime/publisher.hpp"
#include "unav_runtime/qos.hpp"
