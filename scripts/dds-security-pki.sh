#!/usr/bin/env bash
# DDS Security (#19) for a lab whose sim, viewers or operators reach hapticd from other hosts:
# makes the PKI and the signed access-control documents of the OMG DDS Security builtin plugins
# (PKI-DH authentication, Access-Permissions, AES-GCM-GMAC) that Debian's Fast DDS is built with,
# and for each identity a Fast DDS profiles file whose participant profile uses them.
#
#   scripts/dds-security-pki.sh OUT_DIR [--install-dir DIR] [--interface ADDR]... [--peer ADDR]...
#                               [--domain-max N] [--days N]
#   --install-dir  where the files will live on the hosts (the profiles name them by absolute
#                  path); default OUT_DIR. For the services: /etc/haptic/dds-security.
#   --interface    the addresses DDS may use on the host (default 127.0.0.1: one host)
#   --peer         the hosts to discover by unicast (default 127.0.0.1)
# Run it once on a trusted machine. Run it again (with ca.key present) to add what is missing
# or to rewrite the profiles for another host's --interface/--peer: existing keys and
# certificates are kept (remove them to renew); without ca.key the signed documents are kept.
#
# Writes into OUT_DIR:
#   ca.key, ca.pem            one CA for identities and permissions (ca.key stays on this machine)
#   <id>.key, <id>.pem        identity of each participant: hapticd, handsim, operator
#   governance.xml/.p7s       every topic: authenticated participants only, access control on
#                             read and write, discovery, liveliness and data encrypted
#   permissions.xml/.p7s      what each identity may publish and subscribe (docs/messages.md)
#   <id>_profiles.xml         the participant profile <id>_secure of that identity only
# A host gets ca.pem, governance.p7s, permissions.p7s and, of its own identity only, <id>.pem,
# <id>.key (owned by the service's user, mode 600: install -o hapticd -m 600 hapticd.key ...)
# and <id>_profiles.xml, at --install-dir. Then daemon.yaml: dds: {profiles_file:
# DIR/hapticd_profiles.xml, participant_profile: hapticd_secure}; sim.yaml likewise with
# handsim (docs/messages.md, "DDS Security"). A participant without a certificate of this CA is
# not matched at all; an identity gets only its own grant's topics.
set -euo pipefail

usage() { sed -n '2,30p' "$0"; }
OUT=""
DOMAIN_MAX=232
DAYS=3650
INTERFACES=()
PEERS=()
INSTALL_DIR=""
need() { [[ $# -ge 2 && -n "$2" ]] || { echo "dds-security-pki.sh: $1 needs a value" >&2; exit 2; }; }
while [[ $# -gt 0 ]]; do
    case "$1" in
        --install-dir) need "$@"; INSTALL_DIR="$2"; shift 2 ;;
        --interface) need "$@"; INTERFACES+=("$2"); shift 2 ;;
        --peer) need "$@"; PEERS+=("$2"); shift 2 ;;
        --domain-max) need "$@"; DOMAIN_MAX="$2"; shift 2 ;;
        --days) need "$@"; DAYS="$2"; shift 2 ;;
        -h|--help) usage; exit 0 ;;
        -*) echo "dds-security-pki.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
        *) [[ -z "$OUT" ]] || { echo "dds-security-pki.sh: one OUT_DIR only" >&2; exit 2; }
           OUT="$1"; shift ;;
    esac
done
[[ -n "$OUT" ]] || { usage >&2; exit 2; }
[[ ${#INTERFACES[@]} -gt 0 ]] || INTERFACES=(127.0.0.1)
[[ ${#PEERS[@]} -gt 0 ]] || PEERS=(127.0.0.1)
[[ "$DOMAIN_MAX" =~ ^[0-9]+$ && "$DOMAIN_MAX" -le 232 ]] ||
    { echo "dds-security-pki.sh: --domain-max must be 0..232" >&2; exit 2; }
[[ "$DAYS" =~ ^[1-9][0-9]*$ ]] || { echo "dds-security-pki.sh: --days must be a positive number" >&2; exit 2; }
for address in "${INTERFACES[@]}" "${PEERS[@]}"; do
    [[ "$address" =~ ^[0-9]{1,3}(\.[0-9]{1,3}){3}$ ]] ||
        { echo "dds-security-pki.sh: '$address' is not an IPv4 address" >&2; exit 2; }
done
command -v openssl > /dev/null || { echo "dds-security-pki.sh: openssl missing (apt install openssl)" >&2; exit 1; }
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
INSTALL_DIR="${INSTALL_DIR:-$OUT}"
[[ "$INSTALL_DIR" == /* ]] || { echo "dds-security-pki.sh: --install-dir must be absolute" >&2; exit 2; }
umask 077

IDENTITIES=(hapticd handsim operator)
# A day back: Fast DDS reads the grant's dates as the host's local time, so a host west of
# UTC, or one whose clock is a little behind, would otherwise see the grant not yet valid.
NOT_BEFORE="$(date -u -d '-1 day' +%Y-%m-%dT%H:%M:%S)"
NOT_AFTER="$(date -u -d "+$DAYS days" +%Y-%m-%dT%H:%M:%S)"

if [[ ! -e "$OUT/ca.pem" ]]; then
    [[ ! -e "$OUT/ca.key" ]] || { echo "dds-security-pki.sh: $OUT/ca.key without ca.pem" >&2; exit 1; }
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
    [[ -e "$OUT/ca.key" ]] || { echo "dds-security-pki.sh: $id.pem missing and no ca.key to sign it" >&2; exit 1; }
    printf 'basicConstraints=critical,CA:FALSE\nkeyUsage=critical,digitalSignature,keyAgreement\n' \
        > "$OUT/$id.ext"
    openssl x509 -req -in "$OUT/$id.csr" -CA "$OUT/ca.pem" -CAkey "$OUT/ca.key" \
        -CAcreateserial -sha256 -days "$DAYS" -extfile "$OUT/$id.ext" -out "$OUT/$id.pem"
    rm -f "$OUT/$id.ext"
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
    if [[ -e "$OUT/ca.key" ]]; then
        openssl smime -sign -in "$OUT/$document.xml" -text -out "$OUT/$document.p7s" \
            -signer "$OUT/ca.pem" -inkey "$OUT/ca.key"
    elif [[ ! -e "$OUT/$document.p7s" ]]; then
        echo "dds-security-pki.sh: $document.p7s missing and no ca.key to sign it" >&2; exit 1
    fi
done

profile() {
    local id="$1"
    cat <<EOF
    <participant profile_name="${id}_secure">
      <rtps>
        <name>$id</name>
        <userTransports><transport_id>haptic_udp_secure_$id</transport_id></userTransports>
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
            <property><name>dds.sec.auth.builtin.PKI-DH.identity_ca</name><value>file://$INSTALL_DIR/ca.pem</value></property>
            <property><name>dds.sec.auth.builtin.PKI-DH.identity_certificate</name><value>file://$INSTALL_DIR/$id.pem</value></property>
            <property><name>dds.sec.auth.builtin.PKI-DH.private_key</name><value>file://$INSTALL_DIR/$id.key</value></property>
            <property><name>dds.sec.access.plugin</name><value>builtin.Access-Permissions</value></property>
            <property><name>dds.sec.access.builtin.Access-Permissions.permissions_ca</name><value>file://$INSTALL_DIR/ca.pem</value></property>
            <property><name>dds.sec.access.builtin.Access-Permissions.governance</name><value>file://$INSTALL_DIR/governance.p7s</value></property>
            <property><name>dds.sec.access.builtin.Access-Permissions.permissions</name><value>file://$INSTALL_DIR/permissions.p7s</value></property>
            <property><name>dds.sec.crypto.plugin</name><value>builtin.AES-GCM-GMAC</value></property>
          </properties>
        </propertiesPolicy>
      </rtps>
    </participant>
EOF
}
for id in "${IDENTITIES[@]}"; do
    {
        echo '<?xml version="1.0" encoding="UTF-8"?>'
        echo "<!-- Written by scripts/dds-security-pki.sh: the DDS Security participant profile of $id. -->"
        echo '<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">'
        echo '  <profiles>'
        echo '    <transport_descriptors><transport_descriptor>'
        echo "      <transport_id>haptic_udp_secure_$id</transport_id><type>UDPv4</type>"
        printf '      <interfaceWhiteList>'
        for address in "${INTERFACES[@]}"; do printf '<address>%s</address>' "$address"; done
        echo '</interfaceWhiteList>'
        echo '    </transport_descriptor></transport_descriptors>'
        profile "$id"
        echo '  </profiles>'
        echo '</dds>'
    } > "$OUT/${id}_profiles.xml"
done
chmod 600 "$OUT"/*.key
chmod 644 "$OUT"/*.pem "$OUT"/*.xml "$OUT"/*.p7s
echo "dds-security-pki.sh: $OUT (hapticd_profiles.xml, handsim_profiles.xml, operator_profiles.xml; files named at $INSTALL_DIR)"
