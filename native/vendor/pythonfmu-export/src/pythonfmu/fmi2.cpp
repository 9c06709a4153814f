
#include "Logger.hpp"
#include "SlaveInstance.hpp"
#include "fmi/fmi2Functions.h"
#include "fmu_except.hpp"

#include <cctype>
#include <exception>
#include <limits>
#include <memory>
#include <optional>

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

// A struct that holds all the data for one model instance.
struct Fmi2Component
{

    Fmi2Component(std::unique_ptr<pythonfmu::SlaveInstance> slave, std::unique_ptr<Fmi2Logger> logger)
        : lastSuccessfulTime{std::numeric_limits<double>::quiet_NaN()}
        , slave(std::move(slave))
        , logger(std::move(logger))
    { }

    double lastSuccessfulTime{0};
    bool wantsToTerminate{false};

    std::unique_ptr<pythonfmu::SlaveInstance> slave;
    std::unique_ptr<Fmi2Logger> logger;
};


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

    try {

        auto instance = pythonfmu::createInstance(
            {logger.get(),
                visible == fmi2True,
                instanceName,
                resources,
                nullptr});

        auto component = std::make_unique<Fmi2Component>(std::move(instance), std::move(logger));
        return component.release();
    } catch (const std::exception& e) {
        logger->log(fmi2Fatal, e.what());
        return nullptr;
    }
}


void fmi2FreeInstance(fmi2Component c)
{
    if (c) {
        const auto component = static_cast<Fmi2Component*>(c);
        delete component;
    }
}


fmi2Status fmi2SetDebugLogging(
    fmi2Component c,
    fmi2Boolean loggingOn,
    size_t nCategories,
    const fmi2String categories[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance

    std::vector<std::string> categoriesVec;
    // navfmu patch: a NULL category array or entry is refused, not read
    for (size_t i = 0; i < nCategories; ++i) {
        if (categories == nullptr || categories[i] == nullptr) {
            component->logger->log(fmi2Error,
                "fmi2SetDebugLogging: category " + std::to_string(i) + " of " +
                    std::to_string(nCategories) + " is NULL (the debug logging was not changed)");
            return fmi2Error;
        }
    }
    if (nCategories > 0) {
        // Convert categories to std::vector<std::string>
        categoriesVec.reserve(nCategories);
        for (size_t i = 0; i < nCategories; ++i) {
            categoriesVec.emplace_back(categories[i]);
        }
    }

    component->logger->setDebugLogging(loggingOn, categoriesVec);

    return fmi2OK;
}


fmi2Status fmi2SetupExperiment(
    fmi2Component c,
    fmi2Boolean toleranceDefined,
    fmi2Real tolerance,
    fmi2Real startTime,
    fmi2Boolean stopTimeDefined,
    fmi2Real stopTime)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SetupExperiment(
            startTime,
            stopTimeDefined ? std::optional(stopTime) : std::nullopt,
            toleranceDefined ? std::optional(tolerance) : std::nullopt);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->EnterInitializationMode();
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->ExitInitializationMode();
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2Terminate(fmi2Component c)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->Terminate();
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2Reset(fmi2Component c)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->Reset();
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2GetReal(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Real value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->GetReal(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2GetInteger(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Integer value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->GetInteger(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2GetBoolean(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Boolean value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->GetBoolean(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2GetString(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2String value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->GetString(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2SetReal(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Real value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SetReal(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2SetInteger(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Integer value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SetInteger(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2SetBoolean(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Boolean value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SetBoolean(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2SetString(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2String value[])
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SetString(vr, nvr, value);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}


fmi2Status fmi2GetFMUstate(
    fmi2Component c,
    fmi2FMUstate* state)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->GetFMUstate(*state);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2SetFMUstate(
    fmi2Component c,
    fmi2FMUstate state)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SetFMUstate(state);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2FreeFMUstate(
    fmi2Component c,
    fmi2FMUstate* state)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->FreeFMUstate(*state);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2SerializedFMUstateSize(
    fmi2Component c,
    fmi2FMUstate state,
    size_t* size)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        *size = component->slave->SerializedFMUstateSize(state);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2SerializeFMUstate(
    fmi2Component c,
    fmi2FMUstate state,
    fmi2Byte bytes[],
    size_t size)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->SerializeFMUstate(state, bytes, size);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2DeSerializeFMUstate(
    fmi2Component c,
    const fmi2Byte bytes[],
    size_t size,
    fmi2FMUstate* state)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        component->slave->DeSerializeFMUstate(bytes, size, *state);
        return fmi2OK;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
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
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Error,
        "FMI function not supported: fmi2GetDirectionalDerivative");
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2Integer[],
    const fmi2Real[])
{
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Error,
        "FMI function not supported: fmi2SetRealInputDerivatives");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2Integer[],
    fmi2Real[])
{
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Error,
        "FMI function not supported: fmiGetRealOutputDerivatives");
    return fmi2Error;
}

fmi2Status fmi2DoStep(
    fmi2Component c,
    fmi2Real currentCommunicationPoint,
    fmi2Real communicationStepSize,
    fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    try {
        double endTime = currentCommunicationPoint;
        const auto ok = component->slave->DoStep(
            currentCommunicationPoint,
            communicationStepSize);
        if (ok) {
            component->lastSuccessfulTime =
                currentCommunicationPoint + communicationStepSize;
            return fmi2OK;
        }

        component->lastSuccessfulTime = endTime;
        component->wantsToTerminate = true;
        return fmi2Discard;
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    }
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Error,
        "FMI function not supported: fmi2CancelStep");
    return fmi2Error;
}


/* Inquire slave status */
fmi2Status fmi2GetStatus(
    fmi2Component c,
    const fmi2StatusKind,
    fmi2Status*)
{
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Error,
        "FMI function not supported: fmi2GetStatus");
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Real* value)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    if (s == fmi2LastSuccessfulTime) {
        *value = component->lastSuccessfulTime;
        return fmi2OK;
    } else {
        component->logger->log(
            fmi2Discard,
            "Invalid status inquiry for fmi2GetRealStatus");
        return fmi2Discard;
    }
}

fmi2Status fmi2GetIntegerStatus(
    fmi2Component c,
    const fmi2StatusKind,
    fmi2Integer*)
{
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Discard,
        "FMI function not supported: fmi2GetIntegerStatus");
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Boolean* value)
{
    const auto component = static_cast<Fmi2Component*>(c);
    if (component == nullptr) return fmi2Error; // navfmu patch: no instance
    if (s == fmi2Terminated) {
        *value = component->wantsToTerminate ? fmi2True : fmi2False;
        return fmi2OK;
    }
    component->logger->log(
        fmi2Discard, "FMI function not supported: fmi2GetBooleanStatus");
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(
    fmi2Component c,
    const fmi2StatusKind,
    fmi2String*)
{
    if (c == nullptr) return fmi2Error; // navfmu patch: no instance
    static_cast<Fmi2Component*>(c)->logger->log(
        fmi2Discard, "FMI function not supported: fmi2GetStringStatus");
    return fmi2Discard;
}
}
