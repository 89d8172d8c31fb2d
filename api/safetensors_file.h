// Loading a safetensors file named by an API caller: an I/O problem (missing,
// unreadable, a FIFO or device) fails with ROADNN_ERROR_IO, a malformed file with the
// weights::Error that the caller's guarded() maps to its own status.
#pragma once

#include "weights/safetensors.h"

namespace roadnn_api {

weights::SafeTensors load_safetensors_file(const char* path);

}  // namespace roadnn_api
