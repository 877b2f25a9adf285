#!/usr/bin/env bash
# Makes the DDS Security files of a team (issue 22 item 4; README "Secured bus"): one CA (ECDSA P-256) that signs
# every participant's certificate and the governance and permissions documents, then one folder per participant
# holding what that participant needs, with the file names of a ROS 2 (SROS2) enclave:
#   OUT/ca/ca.key, OUT/ca/ca.cert.pem            the CA (keep ca.key off the vehicles)
#   OUT/governance.xml                           the governance document (signed copy in every folder)
#   OUT/NAME/identity_ca.cert.pem                = the CA's certificate (identity CA)
#   OUT/NAME/permissions_ca.cert.pem             = the CA's certificate (permissions CA)
#   OUT/NAME/governance.p7s                      the signed governance document
#   OUT/NAME/cert.pem, OUT/NAME/key.pem          NAME's certificate (subject CN=NAME) and private key
#   OUT/NAME/permissions.xml, permissions.p7s    NAME's permissions, and signed
# Governance: no unauthenticated participant joins; discovery, liveliness, RTPS messages, metadata and data are all
# encrypted (AES-GCM); every topic is access-controlled.
# Permissions of a team participant NAME (a vehicle, the ground station, a UAV relay, an operator console): write
# our topics ugvsense/* only in the partition PARTITION.NAME (so it can write only in its own name: the receiver
# checks that a sample's sender is the writer's partition), read them in PARTITION.* (everyone's), write the ROS 2
# topics rt/NS/* of its own namespace (NS = NAME without its - : ugv-1 -> ugv1) and ros_discovery_info (ROS 2 tools
# list it as a node), and read rt/*.
# Permissions of a ROS 2 node (--ros NAME): every ROS 2 topic (rt/*, rq/*, rr/*, ros_discovery_info) in the
# default partition, none of ours: give its folder to the node as its SROS2 enclave.
# The CA's subject is "CN=ugvsense team CA <16 random hex digits>": its own to this team, so a participant
# can tell a peer of another team's CA (which names its CA in discovery) from a handshake of its own team that
# stalled (ugvsense joins the bus again only for the latter).
# A CA already in OUT is reused (add a vehicle later); an existing participant folder is replaced.
# Usage: make_security.sh OUT --partition P [--days N] [--ros NAME]... NAME...
set -euo pipefail

usage() { echo "usage: make_security.sh OUT --partition P [--days N] [--ros NAME]... NAME..." >&2; exit 2; }
[ $# -ge 1 ] || usage
out=$1; shift
partition="" days=3650 names=() ros=()
while [ $# -gt 0 ]; do
    case $1 in
        --partition) [ $# -ge 2 ] || usage; partition=$2; shift 2 ;;
        --days) [ $# -ge 2 ] || usage; days=$2; shift 2 ;;
        --ros) [ $# -ge 2 ] || usage; ros+=("$2"); shift 2 ;;
        -*) usage ;;
        *) names+=("$1"); shift ;;
    esac
done
[ -n "$partition" ] || { echo "make_security.sh: --partition is required (the config's dds.partition)" >&2; exit 2; }
[ ${#names[@]} -gt 0 ] || [ ${#ros[@]} -gt 0 ] || usage
for n in "${names[@]}" "${ros[@]}"; do
    [[ $n =~ ^[A-Za-z0-9_-]{1,64}$ ]] ||
        { echo "make_security.sh: '$n': a name is 1 to 64 letters, digits, _ and - (the vehicle_id)" >&2; exit 2; }
done
command -v openssl >/dev/null || { echo "make_security.sh: openssl is not installed (apt-get install openssl)" >&2; exit 1; }

mkdir -p "$out/ca"
ca_key=$out/ca/ca.key ca_cert=$out/ca/ca.cert.pem
if [ ! -s "$ca_key" ] || [ ! -s "$ca_cert" ]; then
    openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$ca_key" 2>/dev/null
    chmod 600 "$ca_key"
    openssl req -x509 -new -key "$ca_key" -subj "/CN=ugvsense team CA $(openssl rand -hex 8)" -days "$days" \
        -sha256 \
        -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature" -out "$ca_cert"
fi
not_before=$(date -u +%Y-%m-%dT%H:%M:%S -d "-1 day")
not_after=$(date -u +%Y-%m-%dT%H:%M:%S -d "+$days days")
# Domains 0-230: Cyclone DDS (rmw_cyclonedds_cpp, a ROS 2 node's DDS) cannot parse a governance or permissions
# document naming a domain above 230 and the node then cannot start (found by system.cyclone-interop-secured).
domains="<domains><id_range><min>0</min><max>230</max></id_range></domains>"

cat >"$out/governance.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      $domains
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
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

rules() { # NAME ROS: the allow rule's publish/subscribe elements
    local name=$1 ros_node=$2 ns
    if [ "$ros_node" = yes ]; then
        for t in "rt/*" "rq/*" "rr/*" "ros_discovery_info"; do
            echo "        <publish><topics><topic>$t</topic></topics></publish>"
            echo "        <subscribe><topics><topic>$t</topic></topics></subscribe>"
        done
        return
    fi
    ns=$(tr -cd 'A-Za-z0-9_' <<<"$name")
    [[ -z $ns || $ns =~ ^[0-9] ]] && ns="ugv_$ns" # as the service derives dds.ros_namespace from vehicle_id
    cat <<XML
        <publish><topics><topic>ugvsense/*</topic></topics><partitions><partition>$partition.$name</partition></partitions></publish>
        <subscribe><topics><topic>ugvsense/*</topic></topics><partitions><partition>$partition.*</partition></partitions></subscribe>
        <publish><topics><topic>rt/$ns/*</topic><topic>ros_discovery_info</topic></topics></publish>
        <subscribe><topics><topic>rt/*</topic></topics></subscribe>
XML
}

participant() { # NAME ROS
    local name=$1 dir=$out/$1
    rm -rf "$dir" && mkdir -p "$dir"
    openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$dir/key.pem" 2>/dev/null
    chmod 600 "$dir/key.pem"
    openssl req -new -key "$dir/key.pem" -subj "/CN=$name" -out "$dir/cert.csr"
    openssl x509 -req -in "$dir/cert.csr" -CA "$ca_cert" -CAkey "$ca_key" -set_serial "0x$(openssl rand -hex 16)" \
        -days "$days" -sha256 -out "$dir/cert.pem" 2>/dev/null
    rm -f "$dir/cert.csr"
    cat >"$dir/permissions.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$name">
      <subject_name>CN=$name</subject_name>
      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        $domains
$(rules "$name" "$2")
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
    openssl smime -sign -in "$dir/permissions.xml" -text -out "$dir/permissions.p7s" -signer "$ca_cert" -inkey "$ca_key"
    openssl smime -sign -in "$out/governance.xml" -text -out "$dir/governance.p7s" -signer "$ca_cert" -inkey "$ca_key"
    cp "$ca_cert" "$dir/identity_ca.cert.pem"
    cp "$ca_cert" "$dir/permissions_ca.cert.pem"
    echo "$dir: CN=$name$([ "$2" = yes ] && echo ' (ROS 2 enclave)')"
}

for n in "${names[@]}"; do participant "$n" no; done
for n in "${ros[@]}"; do participant "$n" yes; done
