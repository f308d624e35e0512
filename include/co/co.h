/**
 * @file co.h
 * @brief Everything an application or port includes: the CANopen slave core's whole public API.
 */
#ifndef CO_H
#define CO_H
#include "co_abort.h"
#include "co_config.h"
#include "co_node.h"
#include "co_od.h"
#include "co_port.h"
#include "co_types.h"
#include "co_version.h"
#endif /* CO_H */
