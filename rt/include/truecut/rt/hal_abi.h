/* truecut HAL component ABI, version 1.
 *
 * A component is a shared library (`NAME.so`) that `loadrt NAME k=v ...`
 * opens at run time, or a built-in that registers the same two functions.
 * The library exports, with C linkage:
 *
 *   int  truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
 *                               int argc, const char* const* argv,
 *                               void** module_state);
 *   void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
 *                               void* module_state);
 *
 * They play the parts of LinuxCNC's rtapi_app_main()/rtapi_app_exit():
 * init creates components, pins, parameters and functions through `api`
 * (argv holds the loadrt arguments as "key=value" strings) and returns 0,
 * or a negative errno after calling api->set_error() with a reason. exit is
 * called once when the HAL is torn down; pins and functions are removed by
 * the HAL afterwards. The library links against nothing of truecut: every
 * service comes through the function table, so a component built against
 * ABI version 1 keeps working as long as the table's layout does.
 *
 * Pins work as in LinuxCNC: the component owns a pointer per pin and hands
 * its address to pin_new(); the HAL points it at the pin's own storage
 * (unlinked) or at the storage of the signal the pin is linked to. Reading
 * or writing a pin is one dereference. Parameters point at storage the
 * component owns (use api->alloc for it).
 *
 * Functions (`void f(void* arg, long period_ns)`) run in a servo thread: they
 * must not allocate, lock, block, throw or do I/O. Everything else in the
 * table is for init time, except request_stop which is real-time safe.
 */
#ifndef TRUECUT_RT_HAL_ABI_H
#define TRUECUT_RT_HAL_ABI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TC_HAL_ABI_VERSION 1u

/* Same numeric values as LinuxCNC's hal_type_t, hal_pin_dir_t, hal_param_dir_t. */
typedef enum { TC_HAL_BIT = 1, TC_HAL_FLOAT = 2, TC_HAL_S32 = 3, TC_HAL_U32 = 4 } tc_hal_type_t;
typedef enum { TC_HAL_IN = 16, TC_HAL_OUT = 32, TC_HAL_IO = 48 } tc_hal_pin_dir_t;
typedef enum { TC_HAL_RO = 64, TC_HAL_RW = 192 } tc_hal_param_dir_t;

typedef bool tc_hal_bit_t;
typedef double tc_hal_float_t;
typedef int32_t tc_hal_s32_t;
typedef uint32_t tc_hal_u32_t;

typedef struct tc_hal tc_hal_t; /* opaque HAL context */

typedef void (*tc_hal_funct_t)(void* arg, long period_ns);
/* Runs outside the servo thread, repeatedly while threads run and once after
 * they stop (e.g. to drain a queue the real-time side fills). */
typedef void (*tc_hal_service_t)(void* arg);

typedef enum { TC_HAL_MSG_ERR = 1, TC_HAL_MSG_WARN = 2, TC_HAL_MSG_INFO = 3 } tc_hal_msg_level_t;

typedef struct tc_hal_api {
  uint32_t abi_version; /* TC_HAL_ABI_VERSION of the host */
  uint32_t struct_size; /* sizeof(tc_hal_api_t) of the host */

  /* Returns a component id > 0, or a negative errno. */
  int (*component_new)(tc_hal_t* hal, const char* name);
  /* Marks the component complete; components not ready make the load fail. */
  int (*component_ready)(tc_hal_t* hal, int comp_id);
  /* Zeroed memory that lives as long as the HAL; NULL when out of memory. */
  void* (*alloc)(tc_hal_t* hal, size_t size_bytes);
  int (*pin_new)(tc_hal_t* hal, int comp_id, const char* name, tc_hal_type_t type,
                 tc_hal_pin_dir_t dir, void** data_ptr_addr);
  int (*param_new)(tc_hal_t* hal, int comp_id, const char* name, tc_hal_type_t type,
                   tc_hal_param_dir_t dir, void* data_addr);
  /* Exports `name` for addf; also creates `<name>.time` (s32 pin, ns),
   * `<name>.tmax` (s32 rw parameter, ns) and `<name>.tmax-increased` (bit pin). */
  int (*funct_new)(tc_hal_t* hal, int comp_id, const char* name, tc_hal_funct_t funct, void* arg,
                   int uses_fp);
  int (*service_new)(tc_hal_t* hal, int comp_id, tc_hal_service_t service, void* arg);
  /* Real-time safe: asks the executor to stop after the current cycle. */
  void (*request_stop)(tc_hal_t* hal);
  void (*message)(tc_hal_t* hal, tc_hal_msg_level_t level, const char* text);
  /* Reason shown to the user when init returns an error. */
  void (*set_error)(tc_hal_t* hal, const char* text);
  /* Folder where components write their output files (exists, never NULL). */
  const char* (*output_dir)(tc_hal_t* hal);

  /* Added after the table's first layout: present when api->struct_size
   * covers it (TC_HAL_API_HAS(api, background_service_new)).
   * A service for work that may take long, such as reading and checking a
   * file. In simulated time it runs with the other services, so a run stays
   * repeatable bit for bit; on the wall clock it runs in a thread of its own,
   * so it never delays the other services (the planner's refill among them);
   * under LinuxCNC in the module's non-real-time thread. A background service
   * never runs concurrently with itself. */
  int (*background_service_new)(tc_hal_t* hal, int comp_id, tc_hal_service_t service, void* arg);

  /* Added later still (TC_HAL_API_HAS(api, pending_file_add)); not for the
   * servo cycle. A file the component is writing and will rename or remove
   * (NAME.tmp before it becomes NAME): if the process is ended by SIGINT,
   * SIGTERM or SIGHUP while it is registered, the host removes it, as it
   * removes its own. A component's library has its own copy of any table
   * it keeps, which the host's signal handler does not see; this call puts
   * the name in the host's. Returns a handle >= 0, or a negative errno when
   * the host does not track the file (it is then written without that
   * guarantee; under LinuxCNC, rtapi_app's own signal handling applies). */
  int (*pending_file_add)(tc_hal_t* hal, const char* path);
  /* The file of `handle` is renamed or removed: no longer the host's to remove. */
  void (*pending_file_done)(tc_hal_t* hal, int handle);

  /* Added later still (TC_HAL_API_HAS(api, cycles_ran)). Nonzero once a
   * thread of this HAL has run a cycle; real-time safe. For exit: a
   * component whose files describe what the run did (a machined surface)
   * writes none when no cycle ran: a dry run, or a load that another
   * component or the host's own checks refused. */
  int (*cycles_ran)(tc_hal_t* hal);
} tc_hal_api_t;

/* True when the host's function table has the member `field`. */
#define TC_HAL_API_HAS(api, field) \
  ((api)->struct_size >= offsetof(tc_hal_api_t, field) + sizeof((api)->field))

typedef int (*tc_component_init_fn)(const tc_hal_api_t* api, tc_hal_t* hal, int argc,
                                    const char* const* argv, void** module_state);
typedef void (*tc_component_exit_fn)(const tc_hal_api_t* api, tc_hal_t* hal, void* module_state);

#define TC_COMPONENT_INIT_SYMBOL "truecut_component_init"
#define TC_COMPONENT_EXIT_SYMBOL "truecut_component_exit"

#if defined(__GNUC__)
#define TC_COMPONENT_EXPORT __attribute__((visibility("default")))
#else
#define TC_COMPONENT_EXPORT
#endif

#ifdef __cplusplus
}
#endif

#endif /* TRUECUT_RT_HAL_ABI_H */
