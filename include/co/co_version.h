/**
 * @file co_version.h
 * @brief The version of the core (semantic versioning; the project's version, see CHANGELOG.md).
 *
 * A plain header, not generated, so that the core still builds from src/ and include/ alone in any build
 * system. CMakeLists.txt refuses to configure when its project(VERSION) differs from these numbers.
 */
#ifndef CO_VERSION_H
#define CO_VERSION_H

#define CO_VERSION_MAJOR 0
#define CO_VERSION_MINOR 1
#define CO_VERSION_PATCH 0
#define CO_VERSION_STRING "0.1.0"

/** One number for compile-time checks: #if CO_VERSION >= CO_VERSION_NUMBER(0, 2, 0). */
#define CO_VERSION_NUMBER(major, minor, patch) ((major) * 10000L + (minor) * 100L + (patch))
#define CO_VERSION CO_VERSION_NUMBER(CO_VERSION_MAJOR, CO_VERSION_MINOR, CO_VERSION_PATCH)

#endif /* CO_VERSION_H */
