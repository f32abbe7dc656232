#include "curvemesh/io/mesh_io.hpp"
