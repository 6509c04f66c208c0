#!/usr/bin/env bash
# Makes what DDS Security needs for floorposed and its clients, with openssl: a CA (it
# signs the identities and, as the permissions CA, the two access-control documents), an
# identity (key and certificate) per participant, a governance document that lets no
# unauthenticated participant join and encrypts discovery, liveliness and data on every
# topic, and a permissions document that grants each identity the topics of its role, in
# the domains given:
#
#   daemon     subscribes mesh_delta, headset_pose, command, and the team's marker,
#              plan_pose and status; publishes every output (marker and alert included)
#   headset    the AR app of one device: publishes mesh_delta, headset_pose, command in
#              that device's partition ("device/DEVICE") only; subscribes outputs
#   dashboard  subscribes outputs; publishes markers, and commands in the default
#              partition (a lead's acknowledgements and route requests)
#
# so that only a daemon can publish plan poses, and a headset feeds only its own device's
# daemon. For tests and trials: in the field the CA key lives offline and each device gets
# only its own key.
#
#   tools/make-dds-security.sh OUT_DIR [NAME[:ROLE[:DEVICE]] ...]  (default: floorposed app)
#
# A NAME without a ROLE is a daemon when it starts with "floorposed", a dashboard when it
# starts with "dashboard", else a headset; a headset's DEVICE is its NAME unless given.
#
# Environment: DOMAINS (default "0 230": the domain id range granted), DAYS (validity,
# default 3650), CA_NAME (default "floorpose test CA").
# OUT_DIR gets ca.pem, ca.key, governance.xml(.p7s), permissions.xml(.p7s) and per NAME
# NAME.pem and NAME.key; floorposed.conf's dds.security takes them (docs/security.md).
set -euo pipefail

out="${1:?usage: make-dds-security.sh OUT_DIR [NAME ...]}"
shift
names=("$@")
((${#names[@]})) || names=(floorposed app)
read -r domain_min domain_max <<<"${DOMAINS:-0 230}"
days="${DAYS:-3650}"
ca_name="${CA_NAME:-floorpose test CA}"
command -v openssl >/dev/null || { echo "make-dds-security: openssl not found (apt-get install openssl)" >&2; exit 2; }

# NAME[:ROLE] -> role, the default from the name.
role_of() {
  local spec="$1" name="${1%%:*}"
  if [[ "$spec" == *:* ]]; then
    local rest="${spec#*:}"
    echo "${rest%%:*}"
    return
  fi
  case "$name" in floorposed*) echo daemon ;; dashboard*) echo dashboard ;; *) echo headset ;; esac
}
for spec in "${names[@]}"; do  # every name checked before any key is made
  name="${spec%%:*}"
  [[ "$name" =~ ^[A-Za-z0-9._-]+$ ]] || { echo "make-dds-security: bad name '$name'" >&2; exit 2; }
  case "$(role_of "$spec")" in
    daemon | headset | dashboard) ;;
    *) echo "make-dds-security: '$spec': the role is daemon, headset or dashboard" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
cd "$out"
umask 077
if [[ ! -f ca.key ]]; then
  openssl ecparam -name prime256v1 -genkey -noout -out ca.key
  openssl req -x509 -new -key ca.key -sha256 -days "$days" -subj "/O=floorpose/CN=$ca_name" \
    -out ca.pem 2>/dev/null
fi

not_before="$(date -u +%Y-%m-%dT%H:%M:%S)"
not_after="$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)"
inputs="<topic>floorpose/v1/mesh_delta</topic><topic>floorpose/v1/headset_pose</topic><topic>floorpose/v1/command</topic>"
outputs="<topic>floorpose/v1/plan_pose</topic><topic>floorpose/v1/alignment</topic><topic>floorpose/v1/status</topic><topic>floorpose/v1/plan_track</topic><topic>floorpose/v1/command_reply</topic><topic>floorpose/v1/explored</topic><topic>floorpose/v1/alert</topic><topic>floorpose/v1/marker</topic>"
# What a daemon reads of the rest of the team (markers, teammates' poses and statuses).
team="<topic>floorpose/v1/marker</topic><topic>floorpose/v1/plan_pose</topic><topic>floorpose/v1/status</topic>"
grants=""
made=()
for spec in "${names[@]}"; do
  name="${spec%%:*}"
  role="$(role_of "$spec")"
  device="$name"
  [[ "$spec" == *:*:* ]] && device="${spec##*:}"
  [[ "$device" =~ ^[A-Za-z0-9._-]+$ ]] || { echo "make-dds-security: bad device '$device'" >&2; exit 2; }
  case "$role" in
    daemon) rules="<publish><topics>$outputs</topics></publish>
        <subscribe><topics>$inputs</topics><partitions><partition>*</partition></partitions></subscribe>
        <subscribe><topics>$team</topics></subscribe>" ;;
    headset) rules="<publish><topics>$inputs</topics><partitions><partition>device/$device</partition></partitions></publish>
        <subscribe><topics>$outputs</topics></subscribe>" ;;
    dashboard) rules="<subscribe><topics>$outputs</topics></subscribe>
        <publish><topics><topic>floorpose/v1/marker</topic><topic>floorpose/v1/command</topic></topics></publish>" ;;
  esac
  if [[ "$role" == headset ]]; then made+=("$name (headset of $device)"); else made+=("$name ($role)"); fi
  openssl ecparam -name prime256v1 -genkey -noout -out "$name.key"
  openssl req -new -key "$name.key" -subj "/O=floorpose/CN=$name" -out "$name.csr" 2>/dev/null
  openssl x509 -req -in "$name.csr" -CA ca.pem -CAkey ca.key -CAcreateserial -sha256 \
    -days "$days" -out "$name.pem" 2>/dev/null
  rm -f "$name.csr"
  subject="$(openssl x509 -in "$name.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')"
  grants+="
    <grant name=\"$name\">
      <subject_name>$subject</subject_name>
      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        <domains><id_range><min>$domain_min</min><max>$domain_max</max></id_range></domains>
        $rules
      </allow_rule>
      <default>DENY</default>
    </grant>"
done

cat >governance.xml <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>$domain_min</min><max>$domain_max</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
XML

cat >permissions.xml <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>$grants
  </permissions>
</dds>
XML

for doc in governance permissions; do
  openssl smime -sign -in "$doc.xml" -text -out "$doc.p7s" -signer ca.pem -inkey ca.key
done
chmod 0644 ca.pem governance.p7s permissions.p7s ./*.pem
echo "make-dds-security: $(pwd): CA ca.pem; identities ${made[*]}; governance.p7s, permissions.p7s"
