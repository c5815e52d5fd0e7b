#!/usr/bin/env bash
# DDS Security (#19) for a lab whose sim, viewers or operators reach hapticd from other hosts:
# makes the PKI and the signed access-control documents of the OMG DDS Security builtin plugins
# (PKI-DH authentication, Access-Permissions, AES-GCM-GMAC) that Debian's Fast DDS is built with,
# and a Fast DDS profiles file whose participant profiles use them.
#
#   scripts/dds-security-pki.sh OUT_DIR [--interface ADDR]... [--peer ADDR]... [--domain-max N]
#                               [--days N]
# --interface: the addresses DDS may use on this host (default 127.0.0.1: one host); --peer:
# the hosts to discover by unicast (default 127.0.0.1). Run it once; copy OUT_DIR to each host
# with that host's --interface/--peer, without ca.key.
#
# Writes into OUT_DIR (created; existing files are not overwritten, remove them to renew):
#   ca.key, ca.pem            one CA for identities and permissions (keep ca.key offline)
#   <id>.key, <id>.pem        identity of each participant: hapticd, handsim, operator
#   governance.xml/.p7s       every topic: authenticated participants only, access control on
#                             read and write, data and discovery encrypted
#   permissions.xml/.p7s      who may publish and subscribe what:
#                               hapticd  publishes haptic/* and subscribes sim/*, haptic/command
#                               handsim  publishes sim/* and tracking/*, subscribes haptic/* and
#                                        tracking/*
#                               operator publishes haptic/command, subscribes haptic/* and sim/status
#   dds_security_profiles.xml participant profiles hapticd_secure, handsim_secure and
#                             operator_secure (absolute paths into OUT_DIR)
# Then in daemon.yaml: dds: {profiles_file: OUT_DIR/dds_security_profiles.xml,
# participant_profile: hapticd_secure}, and in sim.yaml the same with handsim_secure
# (docs/hapticd.md, "DDS Security"). A participant without a certificate of this CA is not
# matched at all; one with another identity's certificate gets only that identity's topics.
set -euo pipefail

usage() { sed -n '2,29p' "$0"; }
OUT=""
DOMAIN_MAX=232
DAYS=3650
INTERFACES=()
PEERS=()
while [[ $# -gt 0 ]]; do
    case "$1" in
        --interface) INTERFACES+=("$2"); shift 2 ;;
        --peer) PEERS+=("$2"); shift 2 ;;
        --domain-max) DOMAIN_MAX="$2"; shift 2 ;;
        --days) DAYS="$2"; shift 2 ;;
        -h|--help) usage; exit 0 ;;
        -*) echo "dds-security-pki.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
        *) [[ -z "$OUT" ]] || { echo "dds-security-pki.sh: one OUT_DIR only" >&2; exit 2; }
           OUT="$1"; shift ;;
    esac
done
[[ -n "$OUT" ]] || { usage >&2; exit 2; }
[[ ${#INTERFACES[@]} -gt 0 ]] || INTERFACES=(127.0.0.1)
[[ ${#PEERS[@]} -gt 0 ]] || PEERS=(127.0.0.1)
command -v openssl > /dev/null || { echo "dds-security-pki.sh: openssl missing (apt install openssl)" >&2; exit 1; }
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
umask 077

IDENTITIES=(hapticd handsim operator)
NOT_BEFORE="$(date -u +%Y-%m-%dT%H:%M:%S)"
NOT_AFTER="$(date -u -d "+$DAYS days" +%Y-%m-%dT%H:%M:%S)"

if [[ ! -e "$OUT/ca.pem" ]]; then
    openssl ecparam -name prime256v1 -genkey -noout -out "$OUT/ca.key"
    openssl req -x509 -new -key "$OUT/ca.key" -sha256 -days "$DAYS" -subj "/O=haptic/CN=haptic CA" \
        -out "$OUT/ca.pem"
fi
for id in "${IDENTITIES[@]}"; do
    [[ -e "$OUT/$id.pem" ]] && continue
    openssl ecparam -name prime256v1 -genkey -noout -out "$OUT/$id.key.ec"
    # PKCS#8, the form Fast DDS's PKI-DH plugin loads.
    openssl pkcs8 -topk8 -nocrypt -in "$OUT/$id.key.ec" -out "$OUT/$id.key"
    rm -f "$OUT/$id.key.ec"
    openssl req -new -key "$OUT/$id.key" -subj "/O=haptic/CN=$id" -out "$OUT/$id.csr"
    openssl x509 -req -in "$OUT/$id.csr" -CA "$OUT/ca.pem" -CAkey "$OUT/ca.key" \
        -CAcreateserial -sha256 -days "$DAYS" -out "$OUT/$id.pem" 2> /dev/null
    rm -f "$OUT/$id.csr"
done

domains="<domains><id_range><min>0</min><max>$DOMAIN_MAX</max></id_range></domains>"
cat > "$OUT/governance.xml" <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      $domains
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
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
EOF

# grant <identity> <published topics...> -- <subscribed topics...>
grant() {
    local id="$1"; shift
    local publish="" subscribe="" side=publish
    for topic in "$@"; do
        if [[ "$topic" == "--" ]]; then side=subscribe; continue; fi
        if [[ $side == publish ]]; then publish+="<topic>$topic</topic>"; else subscribe+="<topic>$topic</topic>"; fi
    done
    cat <<EOF
    <grant name="$id">
      <subject_name>CN=$id,O=haptic</subject_name>
      <validity><not_before>$NOT_BEFORE</not_before><not_after>$NOT_AFTER</not_after></validity>
      <allow_rule>
        $domains
        <publish><topics>$publish</topics></publish>
        <subscribe><topics>$subscribe</topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
EOF
}
{
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"'
    echo '     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_permissions.xsd">'
    echo '  <permissions>'
    grant hapticd "haptic/*" -- "sim/*" "haptic/command"
    grant handsim "sim/*" "tracking/*" -- "haptic/*" "tracking/*"
    grant operator "haptic/command" -- "haptic/*" "sim/status"
    echo '  </permissions>'
    echo '</dds>'
} > "$OUT/permissions.xml"

for document in governance permissions; do
    openssl smime -sign -in "$OUT/$document.xml" -text -out "$OUT/$document.p7s" \
        -signer "$OUT/ca.pem" -inkey "$OUT/ca.key"
done

profile() {
    local id="$1"
    cat <<EOF
    <participant profile_name="${id}_secure">
      <rtps>
        <name>$id</name>
        <userTransports><transport_id>haptic_udp_secure</transport_id></userTransports>
        <useBuiltinTransports>false</useBuiltinTransports>
        <builtin>
          <discovery_config>
            <discoveryProtocol>SIMPLE</discoveryProtocol>
            <leaseDuration><sec>10</sec></leaseDuration>
          </discovery_config>
          <initialPeersList>$(for peer in "${PEERS[@]}"; do printf '<locator><udpv4><address>%s</address></udpv4></locator>' "$peer"; done)</initialPeersList>
        </builtin>
        <propertiesPolicy>
          <properties>
            <property><name>dds.sec.auth.plugin</name><value>builtin.PKI-DH</value></property>
            <property><name>dds.sec.auth.builtin.PKI-DH.identity_ca</name><value>file://$OUT/ca.pem</value></property>
            <property><name>dds.sec.auth.builtin.PKI-DH.identity_certificate</name><value>file://$OUT/$id.pem</value></property>
            <property><name>dds.sec.auth.builtin.PKI-DH.private_key</name><value>file://$OUT/$id.key</value></property>
            <property><name>dds.sec.access.plugin</name><value>builtin.Access-Permissions</value></property>
            <property><name>dds.sec.access.builtin.Access-Permissions.permissions_ca</name><value>file://$OUT/ca.pem</value></property>
            <property><name>dds.sec.access.builtin.Access-Permissions.governance</name><value>file://$OUT/governance.p7s</value></property>
            <property><name>dds.sec.access.builtin.Access-Permissions.permissions</name><value>file://$OUT/permissions.p7s</value></property>
            <property><name>dds.sec.crypto.plugin</name><value>builtin.AES-GCM-GMAC</value></property>
          </properties>
        </propertiesPolicy>
      </rtps>
    </participant>
EOF
}
{
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo '<!-- Written by scripts/dds-security-pki.sh: DDS Security participant profiles. -->'
    echo '<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">'
    echo '  <profiles>'
    echo '    <transport_descriptors><transport_descriptor>'
    echo '      <transport_id>haptic_udp_secure</transport_id><type>UDPv4</type>'
    printf '      <interfaceWhiteList>'
    for address in "${INTERFACES[@]}"; do printf '<address>%s</address>' "$address"; done
    echo '</interfaceWhiteList>'
    echo '    </transport_descriptor></transport_descriptors>'
    for id in "${IDENTITIES[@]}"; do profile "$id"; done
    echo '  </profiles>'
    echo '</dds>'
} > "$OUT/dds_security_profiles.xml"
chmod 600 "$OUT"/*.key
chmod 644 "$OUT"/*.pem "$OUT"/*.xml "$OUT"/*.p7s
echo "dds-security-pki.sh: $OUT (profiles: hapticd_secure, handsim_secure, operator_secure)"
