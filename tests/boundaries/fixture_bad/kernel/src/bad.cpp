// Fixture for the boundary check's own test: the kernel must never include this.
#include <yaml-cpp/yaml.h>
