
#ifndef PYTHONFMU_FMU_EXCEPT_HPP
#define PYTHONFMU_FMU_EXCEPT_HPP

#include <stdexcept>
#include <string>

namespace pythonfmu {

    class fatal_error final : public std::runtime_error {
    public:
        explicit fatal_error(const std::string &msg) : std::runtime_error(msg) {}
    };

    // navfmu patch: a call the slave refused (fmi2Error, the instance kept); with
    // instance_failed the instance cannot go on (the FMI error state: only fmi2Reset,
    // fmi2SetFMUstate, the get and state calls and fmi2FreeInstance are allowed after it)
    class refused_call final : public std::runtime_error {
    public:
        refused_call(const std::string &msg, bool instance_failed)
            : std::runtime_error(msg), instance_failed(instance_failed) {}
        const bool instance_failed;
    };


}// namespace pythonfmu

#endif//PYTHONFMU_FMU_EXCEPT_HPP
