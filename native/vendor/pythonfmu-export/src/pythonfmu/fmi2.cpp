
#include "Guards.hpp" // navfmu patch
#include "Logger.hpp"
#include "SlaveInstance.hpp"
#include "fmi/fmi2Functions.h"
#include "fmu_except.hpp"

#include <atomic>
#include <cctype>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <regex>
#include <string>
#include <vector>

namespace
{

class Fmi2Logger : public pythonfmu::PyLogger
{

public:
    explicit Fmi2Logger(const std::string& instanceName, const fmi2CallbackFunctions* f)
        : PyLogger(instanceName)
        , f_(f != nullptr ? *f : fmi2CallbackFunctions{}) // navfmu patch: a copy
    { }

protected:
    // navfmu patch: the category is never NULL (PyLogger::log fills it in); the message goes
    // out as the format string of the host's printf-style logger, so its '%' are doubled;
    // a host without a logger function gets nothing
    void debugLog(fmi2Status s, const std::string& category, const std::string& message) override
    {
        if (f_.logger == nullptr) return;
        std::string text;
        text.reserve(message.size());
        for (const char ch : message) {
            text += ch;
            if (ch == '%') text += '%';
        }
        f_.logger(f_.componentEnvironment, instanceName_.c_str(), s, category.c_str(),
            text.c_str());
    }

private:
    // navfmu patch: the host's structure copied, not its address kept (a host may pass a
    // temporary, as fmpy's container FMU does)
    fmi2CallbackFunctions f_;
};

using pythonfmu::Phase;
namespace allowed = pythonfmu::allowed;

// A struct that holds all the data for one model instance.
struct Fmi2Component
{

    Fmi2Component(std::unique_ptr<pythonfmu::SlaveInstance> slave,
        std::unique_ptr<Fmi2Logger> logger, std::string name)
        : lastSuccessfulTime{std::numeric_limits<double>::quiet_NaN()}
        , slave(std::move(slave))
        , logger(std::move(logger))
        , name(std::move(name))
    { }

    double lastSuccessfulTime{0};
    bool wantsToTerminate{false};

    std::unique_ptr<pythonfmu::SlaveInstance> slave;
    std::unique_ptr<Fmi2Logger> logger;
    std::string name; // navfmu patch: the instance name, the prefix of its messages
    std::atomic<Phase> phase{Phase::instantiated}; // navfmu patch: the FMI state machine's state
    std::string failure; // navfmu patch: the message that put the instance into the error state
};

// navfmu patch: the live instances and FMU states (never destroyed: a host may call in while
// the process exits)
pythonfmu::Registry<Fmi2Component>& registry()
{
    static auto* const live = new pythonfmu::Registry<Fmi2Component>();
    return *live;
}

// navfmu patch: a call refused before it reached the slave, logged as "<instance>: <call>:
// <what>" at fmi2Error
struct Refusal : std::runtime_error
{
    using std::runtime_error::runtime_error;
};

[[noreturn]] void refuse(const Fmi2Component& component, const char* call, const std::string& what)
{
    throw Refusal(component.name + ": " + call + ": " + what);
}

// navfmu patch: every FMI function that takes an instance goes through here.  An unknown or
// freed instance pointer is refused (fmi2Error, nothing logged: there is no logger to log
// through) without being dereferenced; a call FMI 2.0 does not allow in the instance's state
// is refused with one logged line naming the call and the state (the state stays: the
// instance goes on with a legal call, as after any refused call); otherwise ``f`` runs, and
// its exceptions become statuses: a refusal of the slave fmi2Error (the instance in the error
// state when the refusal says it failed), a fatal Python error fmi2Fatal (its Python objects
// are gone: only fmi2FreeInstance is allowed after it).
template <typename F>
fmi2Status guarded(fmi2Component c, const char* call, unsigned allowedPhases, F&& f)
{
    auto* const component = registry().find(c);
    if (component == nullptr) return fmi2Error;
    const Phase before = component->phase;
    if ((allowedPhases & static_cast<unsigned>(before)) == 0) {
        const std::string after = before == Phase::error && !component->failure.empty()
            ? " after the error '" + component->failure + "'"
            : "";
        component->logger->log(fmi2Error, component->name + ": " + call +
                " is not allowed in state " + pythonfmu::phaseName(before) + after +
                " (FMI 2.0 allows it in state " + pythonfmu::phaseNames(allowedPhases) + ")");
        return fmi2Error;
    }
    try {
        const auto status = f(*component);
        if (component->phase != Phase::error) component->failure.clear();
        return status;
    } catch (const pythonfmu::refused_call& e) {
        component->logger->log(fmi2Error, e.what());
        if (e.instance_failed) {
            component->phase = Phase::error;
            const std::string message = e.what(), prefix = component->name + ": ";
            component->failure =
                message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message;
        } else {
            component->phase = before;
        }
        return fmi2Error;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        component->phase = Phase::fatal;
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        component->phase = before;
        return fmi2Error;
    }
}

// navfmu patch: a value reference or value array that is NULL while values are asked for
template <typename V>
void checkArrays(const Fmi2Component& component, const char* call, const fmi2ValueReference vr[],
    size_t nvr, V value)
{
    if (nvr > 0 && (vr == nullptr || value == nullptr)) {
        refuse(component, call, std::string(vr == nullptr ? "the value reference" : "the value") +
                " array is NULL for " + std::to_string(nvr) +
                " values (nothing was read or written)");
    }
}

// navfmu patch: releases a live FMU state (false if it is unknown or was freed)
bool releaseState(Fmi2Component& component, fmi2FMUstate state)
{
    if (!registry().removeState(state)) return false;
    component.slave->FreeFMUstate(state);
    return true;
}

// navfmu patch: an unsupported function answers ``status`` with a message, for a live instance
fmi2Status unsupported(fmi2Component c, const char* call, fmi2Status status)
{
    auto* const component = registry().find(c);
    if (component == nullptr) return fmi2Error;
    component->logger->log(status, std::string("FMI function not supported: ") + call);
    return status;
}

// navfmu patch: the guid attribute of the model description that lies next to the resource
// folder in an unpacked FMU (its first 64 KiB hold the root element), or nullopt where there
// is none to compare with (a host that moved the resources elsewhere)
std::optional<std::string> modelDescriptionGuid(const std::string& resources)
{
    std::filesystem::path folder(resources);
    if (folder.filename().empty()) folder = folder.parent_path(); // "…/resources/"
    std::ifstream in(folder.parent_path() / "modelDescription.xml", std::ios::binary);
    if (!in) return std::nullopt;
    std::string head(64 * 1024, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    const auto root = head.find("<fmiModelDescription");
    const auto end = root == std::string::npos ? root : head.find('>', root);
    if (end == std::string::npos) return std::nullopt;
    const std::string tag = head.substr(root, end - root);
    static const std::regex guid(R"(\sguid\s*=\s*(["'])(.*?)\1)");
    std::smatch match;
    if (!std::regex_search(tag, match, guid)) return std::nullopt;
    return match[2].str();
}

// navfmu patch: the folder a file URI names ("file:///p", "file://localhost/p", "file:/p",
// percent escapes decoded; upstream only removed "file://" and decoded "%20"); anything
// else is taken as a path
std::string resourcePath(const std::string& uri)
{
    std::string path = uri;
    if (path.rfind("file:", 0) == 0) {
        path.erase(0, 5);
        if (path.rfind("//", 0) == 0) {
            const auto slash = path.find('/', 2);
            path.erase(0, slash == std::string::npos ? path.size() : slash);
        }
    }
    std::string decoded;
    for (std::size_t i = 0; i < path.size(); ++i) {
        const auto hex = [](char ch) {
            return std::isxdigit(static_cast<unsigned char>(ch)) != 0;
        };
        if (path[i] == '%' && i + 2 < path.size() && hex(path[i + 1]) && hex(path[i + 2])) {
            decoded += static_cast<char>(std::stoi(path.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            decoded += path[i];
        }
    }
#ifdef _MSC_VER
    if (decoded.size() > 2 && decoded[0] == '/' && decoded[2] == ':') decoded.erase(0, 1);
#endif
    return decoded;
}

} // namespace


// FMI functions
extern "C" {

// =============================================================================
// FMI 2.0 functions
// =============================================================================


const char* fmi2GetTypesPlatform()
{
    return fmi2TypesPlatform;
}


const char* fmi2GetVersion()
{
    return "2.0";
}


fmi2Component fmi2Instantiate(fmi2String instanceName,
    fmi2Type fmuType,
    fmi2String fmuGUID,
    fmi2String fmuResourceLocation,
    const fmi2CallbackFunctions* functions,
    fmi2Boolean visible,
    fmi2Boolean loggingOn)
{

    // navfmu patch: a missing instance name, resource location or callback structure is
    // refused (fmi2Instantiate returns NULL, with a message where a logger was given)
    if (instanceName == nullptr || fmuResourceLocation == nullptr || functions == nullptr) {
        if (functions != nullptr && functions->logger != nullptr) {
            functions->logger(functions->componentEnvironment, instanceName ? instanceName : "",
                fmi2Fatal, "logStatusFatal", "fmi2Instantiate: %s is NULL",
                instanceName == nullptr ? "instanceName" : "fmuResourceLocation");
        }
        return nullptr;
    }

    const auto resources = resourcePath(fmuResourceLocation); // navfmu patch

    auto logger = std::make_unique<Fmi2Logger>(instanceName, functions);
    logger->setDebugLogging(loggingOn);

    // navfmu patch: the GUID must be the model description's (the Reference FMUs' check)
    const auto expected = modelDescriptionGuid(resources);
    if (expected && (fmuGUID == nullptr || *expected != fmuGUID)) {
        logger->log(fmi2Error, std::string(instanceName) + ": fmi2Instantiate: the GUID '" +
                (fmuGUID == nullptr ? "NULL" : fmuGUID) + "' is not this FMU's ('" + *expected +
                "', modelDescription.xml): no instance was created");
        return nullptr;
    }

    try {

        auto instance = pythonfmu::createInstance(
            {logger.get(),
                visible == fmi2True,
                instanceName,
                resources,
                nullptr});

        auto component = std::make_unique<Fmi2Component>(std::move(instance), std::move(logger),
            instanceName);
        registry().add(component.get()); // navfmu patch
        return component.release();
    } catch (const std::exception& e) {
        logger->log(fmi2Fatal, e.what());
        return nullptr;
    }
}


// navfmu patch: an unknown or already freed instance is left alone; one in the middle of its
// fmi2DoStep (a call from another thread) is not freed; the FMU states it made are released
void fmi2FreeInstance(fmi2Component c)
{
    auto* const component = registry().find(c);
    if (component == nullptr) return;
    if (component->phase == Phase::stepInProgress) {
        component->logger->log(fmi2Error, component->name + ": fmi2FreeInstance is not allowed "
                "in state stepInProgress (the instance was not freed)");
        return;
    }
    const auto owned = registry().remove(component);
    if (!owned) return;
    for (auto* state : *owned) component->slave->FreeFMUstate(state);
    delete component;
}


fmi2Status fmi2SetDebugLogging(
    fmi2Component c,
    fmi2Boolean loggingOn,
    size_t nCategories,
    const fmi2String categories[])
{
    return guarded(c, "fmi2SetDebugLogging", allowed::setDebugLogging,
        [&](Fmi2Component& component) {
        // navfmu patch: a NULL category array or entry is refused, not read
        for (size_t i = 0; i < nCategories; ++i) {
            if (categories == nullptr || categories[i] == nullptr) {
                refuse(component, "fmi2SetDebugLogging", "category " + std::to_string(i) +
                        " of " + std::to_string(nCategories) +
                        " is NULL (the debug logging was not changed)");
            }
        }
        std::vector<std::string> categoriesVec(categories, categories + nCategories);
        component.logger->setDebugLogging(loggingOn, categoriesVec);
        return fmi2OK;
    });
}


fmi2Status fmi2SetupExperiment(
    fmi2Component c,
    fmi2Boolean toleranceDefined,
    fmi2Real tolerance,
    fmi2Real startTime,
    fmi2Boolean stopTimeDefined,
    fmi2Real stopTime)
{
    return guarded(c, "fmi2SetupExperiment", allowed::setupExperiment,
        [&](Fmi2Component& component) {
        component.slave->SetupExperiment(
            startTime,
            stopTimeDefined ? std::optional(stopTime) : std::nullopt,
            toleranceDefined ? std::optional(tolerance) : std::nullopt);
        return fmi2OK;
    });
}


fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return guarded(c, "fmi2EnterInitializationMode", allowed::enterInitializationMode,
        [&](Fmi2Component& component) {
            component.slave->EnterInitializationMode();
            component.phase = Phase::initializationMode;
            return fmi2OK;
        });
}


fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return guarded(c, "fmi2ExitInitializationMode", allowed::exitInitializationMode,
        [&](Fmi2Component& component) {
            component.slave->ExitInitializationMode();
            component.phase = Phase::stepComplete;
            return fmi2OK;
        });
}


fmi2Status fmi2Terminate(fmi2Component c)
{
    return guarded(c, "fmi2Terminate", allowed::terminate, [&](Fmi2Component& component) {
        component.slave->Terminate();
        component.phase = Phase::terminated;
        return fmi2OK;
    });
}


fmi2Status fmi2Reset(fmi2Component c)
{
    return guarded(c, "fmi2Reset", allowed::reset, [&](Fmi2Component& component) {
        component.slave->Reset();
        component.phase = Phase::instantiated;
        component.lastSuccessfulTime = std::numeric_limits<double>::quiet_NaN();
        component.wantsToTerminate = false;
        return fmi2OK;
    });
}


fmi2Status fmi2GetReal(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Real value[])
{
    return guarded(c, "fmi2GetReal", allowed::getValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2GetReal", vr, nvr, value);
        component.slave->GetReal(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2GetInteger(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Integer value[])
{
    return guarded(c, "fmi2GetInteger", allowed::getValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2GetInteger", vr, nvr, value);
        component.slave->GetInteger(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2GetBoolean(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Boolean value[])
{
    return guarded(c, "fmi2GetBoolean", allowed::getValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2GetBoolean", vr, nvr, value);
        component.slave->GetBoolean(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2GetString(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2String value[])
{
    return guarded(c, "fmi2GetString", allowed::getValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2GetString", vr, nvr, value);
        component.slave->GetString(vr, nvr, value);
        return fmi2OK;
    });
}


fmi2Status fmi2SetReal(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Real value[])
{
    return guarded(c, "fmi2SetReal", allowed::setValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2SetReal", vr, nvr, value);
        component.slave->SetReal(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2SetInteger(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Integer value[])
{
    return guarded(c, "fmi2SetInteger", allowed::setValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2SetInteger", vr, nvr, value);
        component.slave->SetInteger(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2SetBoolean(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Boolean value[])
{
    return guarded(c, "fmi2SetBoolean", allowed::setValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2SetBoolean", vr, nvr, value);
        component.slave->SetBoolean(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2SetString(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2String value[])
{
    return guarded(c, "fmi2SetString", allowed::setValues, [&](Fmi2Component& component) {
        checkArrays(component, "fmi2SetString", vr, nvr, value);
        for (size_t i = 0; i < nvr; ++i) {
            if (value[i] == nullptr) {
                refuse(component, "fmi2SetString", "value " + std::to_string(i) +
                        " is NULL (nothing was set)");
            }
        }
        component.slave->SetString(vr, nvr, value);
        return fmi2OK;
    });
}


// navfmu patch: the FMU state functions accept only the live states of this library (an
// unknown or freed one is refused, never dereferenced); fmi2GetFMUstate replaces a live
// *FMUstate it is given (FMI 2.0) and records the state the instance is in, which
// fmi2SetFMUstate restores
fmi2Status fmi2GetFMUstate(
    fmi2Component c,
    fmi2FMUstate* state)
{
    return guarded(c, "fmi2GetFMUstate", allowed::fmuState, [&](Fmi2Component& component) {
        if (state == nullptr) refuse(component, "fmi2GetFMUstate", "the FMUstate pointer is NULL");
        const fmi2FMUstate previous = *state;
        if (previous != nullptr && !registry().statePhase(previous)) {
            refuse(component, "fmi2GetFMUstate", "*FMUstate is neither NULL nor a live state "
                    "of this FMU (unknown or freed)");
        }
        fmi2FMUstate taken = nullptr;
        component.slave->GetFMUstate(taken);
        registry().addState(taken, &component, component.phase);
        if (previous != nullptr) releaseState(component, previous);
        *state = taken;
        return fmi2OK;
    });
}

fmi2Status fmi2SetFMUstate(
    fmi2Component c,
    fmi2FMUstate state)
{
    return guarded(c, "fmi2SetFMUstate", allowed::fmuState, [&](Fmi2Component& component) {
        const auto phase = registry().statePhase(state);
        if (!phase) {
            refuse(component, "fmi2SetFMUstate", "the FMUstate is unknown or was freed (the "
                    "instance keeps its state)");
        }
        component.slave->SetFMUstate(state);
        component.phase = *phase;
        return fmi2OK;
    });
}

fmi2Status fmi2FreeFMUstate(
    fmi2Component c,
    fmi2FMUstate* state)
{
    return guarded(c, "fmi2FreeFMUstate", allowed::fmuState, [&](Fmi2Component& component) {
        if (state == nullptr || *state == nullptr) return fmi2OK; // FMI 2.0: ignored
        if (!releaseState(component, *state)) {
            refuse(component, "fmi2FreeFMUstate", "the FMUstate is unknown or was freed already");
        }
        *state = nullptr;
        return fmi2OK;
    });
}

fmi2Status fmi2SerializedFMUstateSize(
    fmi2Component c,
    fmi2FMUstate state,
    size_t* size)
{
    return guarded(c, "fmi2SerializedFMUstateSize", allowed::fmuState,
        [&](Fmi2Component& component) {
        if (!registry().statePhase(state)) {
            refuse(component, "fmi2SerializedFMUstateSize", "the FMUstate is unknown or was freed");
        }
        if (size == nullptr) refuse(component, "fmi2SerializedFMUstateSize", "size is NULL");
        *size = component.slave->SerializedFMUstateSize(state);
        return fmi2OK;
    });
}

fmi2Status fmi2SerializeFMUstate(
    fmi2Component c,
    fmi2FMUstate state,
    fmi2Byte bytes[],
    size_t size)
{
    return guarded(c, "fmi2SerializeFMUstate", allowed::fmuState, [&](Fmi2Component& component) {
        if (!registry().statePhase(state)) {
            refuse(component, "fmi2SerializeFMUstate", "the FMUstate is unknown or was freed");
        }
        if (bytes == nullptr && size > 0) {
            refuse(component, "fmi2SerializeFMUstate", "bytes is NULL");
        }
        component.slave->SerializeFMUstate(state, bytes, size);
        return fmi2OK;
    });
}

fmi2Status fmi2DeSerializeFMUstate(
    fmi2Component c,
    const fmi2Byte bytes[],
    size_t size,
    fmi2FMUstate* state)
{
    return guarded(c, "fmi2DeSerializeFMUstate", allowed::fmuState, [&](Fmi2Component& component) {
        if (state == nullptr) {
            refuse(component, "fmi2DeSerializeFMUstate", "the FMUstate pointer is NULL");
        }
        if (bytes == nullptr && size > 0) {
            refuse(component, "fmi2DeSerializeFMUstate", "bytes is NULL");
        }
        fmi2FMUstate made = nullptr;
        const auto phase = component.slave->DeSerializeFMUstate(bytes, size, made);
        registry().addState(made, &component, pythonfmu::phaseNamed(phase));
        *state = made;
        return fmi2OK;
    });
}


fmi2Status fmi2GetDirectionalDerivative(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2ValueReference[],
    size_t,
    const fmi2Real[],
    fmi2Real[])
{
    return unsupported(c, "fmi2GetDirectionalDerivative", fmi2Error);
}

fmi2Status fmi2SetRealInputDerivatives(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2Integer[],
    const fmi2Real[])
{
    return unsupported(c, "fmi2SetRealInputDerivatives", fmi2Error);
}

fmi2Status fmi2GetRealOutputDerivatives(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2Integer[],
    fmi2Real[])
{
    return unsupported(c, "fmi2GetRealOutputDerivatives", fmi2Error);
}

fmi2Status fmi2DoStep(
    fmi2Component c,
    fmi2Real currentCommunicationPoint,
    fmi2Real communicationStepSize,
    fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/)
{
    return guarded(c, "fmi2DoStep", allowed::doStep, [&](Fmi2Component& component) {
        component.phase = Phase::stepInProgress; // navfmu patch
        const auto ok = component.slave->DoStep(
            currentCommunicationPoint,
            communicationStepSize);
        if (ok) {
            component.lastSuccessfulTime =
                currentCommunicationPoint + communicationStepSize;
            component.phase = Phase::stepComplete;
            return fmi2OK;
        }

        component.lastSuccessfulTime = currentCommunicationPoint;
        component.wantsToTerminate = true;
        component.phase = Phase::stepFailed;
        return fmi2Discard;
    });
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return unsupported(c, "fmi2CancelStep", fmi2Error);
}


/* Inquire slave status */
fmi2Status fmi2GetStatus(
    fmi2Component c,
    const fmi2StatusKind,
    fmi2Status*)
{
    return unsupported(c, "fmi2GetStatus", fmi2Error);
}

fmi2Status fmi2GetRealStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Real* value)
{
    return guarded(c, "fmi2GetRealStatus", allowed::getStatus, [&](Fmi2Component& component) {
        if (value == nullptr) refuse(component, "fmi2GetRealStatus", "value is NULL");
        if (s == fmi2LastSuccessfulTime) {
            *value = component.lastSuccessfulTime;
            return fmi2OK;
        }
        component.logger->log(fmi2Discard, "Invalid status inquiry for fmi2GetRealStatus");
        return fmi2Discard;
    });
}

fmi2Status fmi2GetIntegerStatus(
    fmi2Component c,
    const fmi2StatusKind,
    fmi2Integer*)
{
    return unsupported(c, "fmi2GetIntegerStatus", fmi2Discard);
}

fmi2Status fmi2GetBooleanStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Boolean* value)
{
    return guarded(c, "fmi2GetBooleanStatus", allowed::getStatus, [&](Fmi2Component& component) {
        if (value == nullptr) refuse(component, "fmi2GetBooleanStatus", "value is NULL");
        if (s == fmi2Terminated) {
            *value = component.wantsToTerminate ? fmi2True : fmi2False;
            return fmi2OK;
        }
        component.logger->log(fmi2Discard, "FMI function not supported: fmi2GetBooleanStatus");
        return fmi2Discard;
    });
}

fmi2Status fmi2GetStringStatus(
    fmi2Component c,
    const fmi2StatusKind,
    fmi2String*)
{
    return unsupported(c, "fmi2GetStringStatus", fmi2Discard);
}
}
