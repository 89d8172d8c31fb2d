// roadnn_version(): the project version CMake configured into roadnn_version.h.
#include "roadnn/roadnn.h"
#include "roadnn_version.h"

extern "C" const char* roadnn_version(void) { return ROADNN_VERSION_STRING; }
