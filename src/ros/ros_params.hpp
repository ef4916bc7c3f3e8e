// acvo::Params from the ROS parameter server and from dynamic_reconfigure.
//
// The private namespace holds the same sections and keys as config/acvo.yaml
// (~selection/target_points, ~paper/ell_policy as a string, ...): the nodelet walks
// acvo::visitParams, so a key added to the core is read here without a change.
#pragma once

#include <string>
#include <vector>

#include <xmlrpcpp/XmlRpcValue.h>

#include "acvo/AcvoConfig.h"
#include "acvo/params.hpp"
#include "nodelet_settings.hpp"

namespace acvo_ros {

// Applies the sections of `private_ns` (the struct of the node's private namespace) on top of
// `params`. Returns one sentence per problem: a wrong type or unknown enum value (that key
// keeps its previous value) or an unknown key in a section (ignored). Does not validate().
std::vector<std::string> applyRosParams(const XmlRpc::XmlRpcValue& private_ns,
                                        acvo::Params& params);

// One sentence per top-level private parameter that is a parameter's key without its section,
// or its dynamic_reconfigure name (`~target_points` for `~selection/target_points`,
// `~paper_ell_init` for `~paper/ell_init`): nothing reads it, and it names `~section/key`, the
// name that is read. The reconfigure server writes its names into the private namespace itself,
// with the values in use: a reconfigure name whose value is that of `params` (the parameters in
// use) is not reported.
std::vector<std::string> sectionlessParameters(const XmlRpc::XmlRpcValue& private_ns,
                                               const acvo::Params& params);
// The top-level names sectionlessParameters looks at (every key and reconfigure name), for
// unknownParameters' `also_known`.
std::vector<std::string> sectionlessNames();

// "section/name=value ..." for every parameter: logged at start and compared to detect a change.
std::string describeParams(const acvo::Params& params);

// The dynamic_reconfigure view of the parameters cfg/Acvo.cfg exposes: each by its key (the
// paper section's as paper_KEY), lost_odom from the nodelet's settings.
acvo::AcvoConfig toConfig(const acvo::Params& params, LostOdom lost_odom);
// The parameters with the reconfigurable ones taken from `config`. Throws
// std::invalid_argument for an unknown enum string.
acvo::Params fromConfig(const acvo::AcvoConfig& config, acvo::Params base);
// The names of cfg/Acvo.cfg that name no parameter (but lost_odom): a typo there would leave an
// option that changes nothing.
std::vector<std::string> reconfigureNamesWithoutParameter();

}  // namespace acvo_ros
