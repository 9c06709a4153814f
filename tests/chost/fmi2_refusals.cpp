// A native FMI 2.0 host in C++ whose logger builds a std::string from the category and the
// message of every call, as OMSimulator does: a NULL category throws std::logic_error
// ("basic_string: construction from null is not valid") out of the callback and ends the
// process with std::terminate (status 134).  It drives one FMU through every refusal path of
// the FMI API with loggingOn = fmi2False and prints, per case, the status of the refused call
// and the messages logged while it ran:
//
//   case NAME status STATUS
//   msg STATUS CATEGORY
//
// Usage: fmi2_refusals LIBRARY GUID RESOURCE_URI EMPTY_URI STEP OUT_VR IN_VR PARAM_VR ARG...
// OUT_VR is a Real output, IN_VR a Real input (or -1 for none), PARAM_VR a Real parameter
// (or -1 for none: the String parameter of the first "s:" argument is set after
// initialization instead);
// each ARG is "s:VR=TEXT" (a String parameter every instance gets before initialization),
// "bad_s:VR=TEXT" (a String value whose initialization must be refused) or "bad_r:VR=VALUE"
// (the same for a Real parameter).  Exit status 0 when every case ran, 1 on a usage or load
// error.
#include <dlfcn.h>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

extern "C" {
#include "fmi2Functions.h"
}

namespace
{

std::vector<std::pair<int, std::string>> messages;

extern "C" void logger(fmi2ComponentEnvironment, fmi2String instance, fmi2Status status,
                       fmi2String category, fmi2String message, ...)
{
    const std::string name(instance), cat(category), format(message);  // as OMSimulator does
    char text[4096];
    va_list args;
    va_start(args, message);
    std::vsnprintf(text, sizeof text, format.c_str(), args);
    va_end(args);
    messages.emplace_back(static_cast<int>(status), cat);
    std::fprintf(stderr, "[%s] %d %s: %s\n", name.c_str(), static_cast<int>(status),
                 cat.c_str(), text);
}

void* lib = nullptr;

template <typename F>
F* symbol(const char* name)
{
    void* f = dlsym(lib, name);
    if (f == nullptr) {
        std::fprintf(stderr, "fmi2_refusals: symbol %s not found\n", name);
        std::exit(1);
    }
    return reinterpret_cast<F*>(f);
}

void report(const char* name, int status)
{
    std::printf("case %s status %d\n", name, status);
    for (const auto& [s, cat] : messages) std::printf("msg %d %s\n", s, cat.c_str());
    messages.clear();
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 9) {
        std::fprintf(stderr, "usage: %s LIBRARY GUID RESOURCE_URI EMPTY_URI STEP OUT_VR IN_VR "
                             "PARAM_VR ARG...\n", argv[0]);
        return 1;
    }
    const char *guid = argv[2], *uri = argv[3], *empty_uri = argv[4];
    const double h = std::atof(argv[5]);
    const fmi2ValueReference out_vr = std::strtoul(argv[6], nullptr, 10);
    const long in_vr = std::strtol(argv[7], nullptr, 10);
    const long param_arg = std::strtol(argv[8], nullptr, 10);
    const auto param_vr = static_cast<fmi2ValueReference>(param_arg >= 0 ? param_arg : 0);
    std::vector<std::pair<fmi2ValueReference, std::string>> strings, bad_strings;
    std::vector<std::pair<fmi2ValueReference, double>> bad_reals;
    for (int i = 9; i < argc; ++i) {
        std::string arg(argv[i]);
        const auto colon = arg.find(':'), eq = arg.find('=');
        if (colon == std::string::npos || eq == std::string::npos || eq < colon) {
            std::fprintf(stderr, "fmi2_refusals: bad argument %s\n", argv[i]);
            return 1;
        }
        const std::string kind = arg.substr(0, colon), value = arg.substr(eq + 1);
        const auto vr = static_cast<fmi2ValueReference>(
            std::strtoul(arg.substr(colon + 1, eq - colon - 1).c_str(), nullptr, 10));
        if (kind == "s") strings.emplace_back(vr, value);
        else if (kind == "bad_s") bad_strings.emplace_back(vr, value);
        else if (kind == "bad_r") bad_reals.emplace_back(vr, std::atof(value.c_str()));
        else {
            std::fprintf(stderr, "fmi2_refusals: bad argument %s\n", argv[i]);
            return 1;
        }
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == nullptr) {
        std::fprintf(stderr, "fmi2_refusals: cannot load %s: %s\n", argv[1], dlerror());
        return 1;
    }
    auto instantiate = symbol<fmi2InstantiateTYPE>("fmi2Instantiate");
    auto free_instance = symbol<fmi2FreeInstanceTYPE>("fmi2FreeInstance");
    auto setup = symbol<fmi2SetupExperimentTYPE>("fmi2SetupExperiment");
    auto enter = symbol<fmi2EnterInitializationModeTYPE>("fmi2EnterInitializationMode");
    auto exit_init = symbol<fmi2ExitInitializationModeTYPE>("fmi2ExitInitializationMode");
    auto do_step = symbol<fmi2DoStepTYPE>("fmi2DoStep");
    auto get_real = symbol<fmi2GetRealTYPE>("fmi2GetReal");
    auto get_integer = symbol<fmi2GetIntegerTYPE>("fmi2GetInteger");
    auto set_real = symbol<fmi2SetRealTYPE>("fmi2SetReal");
    auto set_string = symbol<fmi2SetStringTYPE>("fmi2SetString");
    auto set_debug = symbol<fmi2SetDebugLoggingTYPE>("fmi2SetDebugLogging");
    auto get_state = symbol<fmi2GetFMUstateTYPE>("fmi2GetFMUstate");
    auto deserialize = symbol<fmi2DeSerializeFMUstateTYPE>("fmi2DeSerializeFMUstate");
    auto free_state = symbol<fmi2FreeFMUstateTYPE>("fmi2FreeFMUstate");
    auto derivative = symbol<fmi2GetDirectionalDerivativeTYPE>("fmi2GetDirectionalDerivative");
    auto set_in_der = symbol<fmi2SetRealInputDerivativesTYPE>("fmi2SetRealInputDerivatives");
    auto get_out_der = symbol<fmi2GetRealOutputDerivativesTYPE>("fmi2GetRealOutputDerivatives");
    auto cancel = symbol<fmi2CancelStepTYPE>("fmi2CancelStep");
    auto get_status = symbol<fmi2GetStatusTYPE>("fmi2GetStatus");
    auto get_real_status = symbol<fmi2GetRealStatusTYPE>("fmi2GetRealStatus");
    auto get_int_status = symbol<fmi2GetIntegerStatusTYPE>("fmi2GetIntegerStatus");
    auto get_bool_status = symbol<fmi2GetBooleanStatusTYPE>("fmi2GetBooleanStatus");
    auto get_str_status = symbol<fmi2GetStringStatusTYPE>("fmi2GetStringStatus");

    fmi2CallbackFunctions callbacks = {logger, std::calloc, std::free, nullptr, nullptr};
    auto fresh = [&](const char* resources) {
        return instantiate("host", fmi2CoSimulation, guid, resources, &callbacks, fmi2False,
                           fmi2False);
    };
    auto give_strings = [&](fmi2Component c,
                            const std::vector<std::pair<fmi2ValueReference, std::string>>& s) {
        for (const auto& [vr, text] : s) {
            const char* value = text.c_str();
            set_string(c, &vr, 1, &value);
        }
    };
    // a fresh instance, initialized (or only set up when init is false), messages cleared
    auto ready = [&](bool init) {
        fmi2Component c = fresh(uri);
        if (c == nullptr) {
            std::fprintf(stderr, "fmi2_refusals: fmi2Instantiate failed\n");
            std::exit(1);
        }
        setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        give_strings(c, strings);
        if (init) {
            enter(c);
            if (exit_init(c) != fmi2OK) {
                std::fprintf(stderr, "fmi2_refusals: the instance does not initialize\n");
                std::exit(1);
            }
        }
        messages.clear();
        return c;
    };
    auto on_ready = [&](const char* name, bool init, const std::function<int(fmi2Component)>& f) {
        fmi2Component c = ready(init);
        const int status = f(c);
        free_instance(c);
        report(name, status);
    };

    // instantiation
    fmi2Component none = fresh(empty_uri);
    report("instantiate_without_script", none == nullptr ? 4 : 0);
    if (none != nullptr) free_instance(none);
    none = fresh(nullptr);
    report("instantiate_null_resources", none == nullptr ? 4 : 0);

    // the host's callback structure is gone after fmi2Instantiate (FMI 2.0 does not promise
    // it lives on; fmpy's container FMU passes a temporary): the FMU must have copied it
    {
        auto* temporary = static_cast<fmi2CallbackFunctions*>(std::malloc(sizeof callbacks));
        std::memcpy(static_cast<void*>(temporary), &callbacks, sizeof callbacks);
        fmi2Component c = instantiate("host", fmi2CoSimulation, guid, uri, temporary, fmi2False,
                                      fmi2False);
        std::memset(static_cast<void*>(temporary), 0xff, sizeof callbacks);
        std::free(temporary);
        const fmi2ValueReference vr = 999999;
        fmi2Real v = 0.0;
        const int status = c == nullptr ? -1 : get_real(c, &vr, 1, &v);
        if (c != nullptr) free_instance(c);
        report("callback_structure_released_after_instantiation", status);
    }

    // initialization refused
    int n_bad = 0;
    for (const auto& [vr, text] : bad_strings) {
        fmi2Component c = ready(false);
        give_strings(c, {{vr, text}});
        enter(c);
        const int status = exit_init(c);
        free_instance(c);
        report(("exit_init_string_" + std::to_string(++n_bad)).c_str(), status);
    }
    for (const auto& [vr, value] : bad_reals) {
        fmi2Component c = ready(false);
        set_real(c, &vr, 1, &value);
        enter(c);
        const int status = exit_init(c);
        free_instance(c);
        report(("exit_init_real_" + std::to_string(++n_bad)).c_str(), status);
    }
    on_ready("do_step_before_initialization", false,
             [&](fmi2Component c) { return do_step(c, 0.0, h, fmi2True); });

    // value access
    on_ready("get_unknown_value_reference", true, [&](fmi2Component c) {
        const fmi2ValueReference vr = 999999;
        fmi2Real v = 0.0;
        return get_real(c, &vr, 1, &v);
    });
    on_ready("get_real_as_integer", true, [&](fmi2Component c) {
        fmi2Integer v = 0;
        return get_integer(c, &out_vr, 1, &v);
    });
    on_ready("set_output", true, [&](fmi2Component c) {
        const fmi2Real v = 1.0;
        return set_real(c, &out_vr, 1, &v);
    });
    on_ready("set_fixed_parameter_after_initialization", true, [&](fmi2Component c) {
        if (param_arg < 0 && !strings.empty()) {
            const char* text = strings[0].second.c_str();
            return static_cast<int>(set_string(c, &strings[0].first, 1, &text));
        }
        const fmi2Real v = 0.5;
        return static_cast<int>(set_real(c, &param_vr, 1, &v));
    });

    // steps
    on_ready("do_step_at_wrong_time", true,
             [&](fmi2Component c) { return do_step(c, 10 * h, h, fmi2True); });
    on_ready("do_step_of_zero_size", true,
             [&](fmi2Component c) { return do_step(c, 0.0, 0.0, fmi2True); });
    if (in_vr >= 0) {
        on_ready("do_step_with_nan_input", true, [&](fmi2Component c) {
            const auto vr = static_cast<fmi2ValueReference>(in_vr);
            const fmi2Real v = std::nan("");
            set_real(c, &vr, 1, &v);
            return do_step(c, 0.0, h, fmi2True);
        });
        on_ready("do_step_after_an_error_again", true, [&](fmi2Component c) {
            const auto vr = static_cast<fmi2ValueReference>(in_vr);
            const fmi2Real v = std::nan("");
            set_real(c, &vr, 1, &v);
            do_step(c, 0.0, h, fmi2True);
            messages.clear();
            report("do_step_after_an_error", do_step(c, 0.0, h, fmi2True));  // one message
            return do_step(c, 0.0, h, fmi2True);  // refused again, with its message
        });
    }

    // states
    on_ready("deserialize_foreign_blob", true, [&](fmi2Component c) {
        const char blob[] = "not a state of this FMU";
        fmi2FMUstate state = nullptr;
        const int status = deserialize(c, blob, sizeof blob, &state);
        if (state != nullptr) free_state(c, &state);
        return status;
    });
    on_ready("calls_without_an_instance", true, [&](fmi2Component) {
        fmi2FMUstate state = nullptr;
        fmi2Real v = 0.0;
        const int a = get_state(nullptr, &state), b = get_real(nullptr, &out_vr, 1, &v);
        const int d = do_step(nullptr, 0.0, h, fmi2True), e = cancel(nullptr);
        return a == b && b == d && d == e ? a : -1;
    });

    // logging and functions the FMU does not offer
    on_ready("set_debug_logging_null_category", true, [&](fmi2Component c) {
        const fmi2String categories[] = {"logStatusError", nullptr};
        return set_debug(c, fmi2True, 2, categories);
    });
    on_ready("get_directional_derivative", true, [&](fmi2Component c) {
        fmi2Real dv = 1.0, out = 0.0;
        return derivative(c, &out_vr, 1, &param_vr, 1, &dv, &out);
    });
    on_ready("set_real_input_derivatives", true, [&](fmi2Component c) {
        const fmi2Integer order = 1;
        const fmi2Real v = 0.0;
        return set_in_der(c, &param_vr, 1, &order, &v);
    });
    on_ready("get_real_output_derivatives", true, [&](fmi2Component c) {
        const fmi2Integer order = 1;
        fmi2Real v = 0.0;
        return get_out_der(c, &out_vr, 1, &order, &v);
    });
    on_ready("cancel_step", true, [&](fmi2Component c) { return cancel(c); });
    on_ready("get_status", true, [&](fmi2Component c) {
        fmi2Status s;
        return get_status(c, fmi2DoStepStatus, &s);
    });
    on_ready("get_real_status_of_wrong_kind", true, [&](fmi2Component c) {
        fmi2Real v;
        return get_real_status(c, fmi2DoStepStatus, &v);
    });
    on_ready("get_integer_status", true, [&](fmi2Component c) {
        fmi2Integer v;
        return get_int_status(c, fmi2DoStepStatus, &v);
    });
    on_ready("get_boolean_status_of_wrong_kind", true, [&](fmi2Component c) {
        fmi2Boolean v;
        return get_bool_status(c, fmi2DoStepStatus, &v);
    });
    on_ready("get_string_status", true, [&](fmi2Component c) {
        fmi2String v;
        return get_str_status(c, fmi2PendingStatus, &v);
    });
    return 0;
}
