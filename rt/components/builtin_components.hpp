// Internal: entry points of the components compiled into truecut.
#pragma once

#include "truecut/rt/hal_abi.h"

namespace truecut::rt::hal::builtin {

int siggen_init(const tc_hal_api_t*, tc_hal_t*, int, const char* const*, void**);
void siggen_exit(const tc_hal_api_t*, tc_hal_t*, void*);
int recorder_init(const tc_hal_api_t*, tc_hal_t*, int, const char* const*, void**);
void recorder_exit(const tc_hal_api_t*, tc_hal_t*, void*);

}  // namespace truecut::rt::hal::builtin
