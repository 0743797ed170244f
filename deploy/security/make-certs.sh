#!/usr/bin/env bash
# Creates the DDS Security files of a telegrasp deployment (Fast DDS built-in plugins PKI-DH,
# Access-Permissions, AES-GCM-GMAC) with openssl:
#
#   deploy/security/make-certs.sh OUTDIR [--operator NAME]... [--expired NAME] [--foreign NAME]
#                                        [--days N] [NAME...]
#
#   OUTDIR/ca.pem, ca.key         the certificate authority (keep ca.key off client machines)
#   OUTDIR/governance.xml, .p7s   domain rules, S/MIME-signed by the CA (what Fast DDS reads)
#   OUTDIR/<name>/cert.pem, key.pem, permissions.xml, permissions.p7s   one identity each:
#     server                the telegrasp-server (always made): writes every output, reads
#                           ControllerState and SceneCommand
#     NAME                  a client: writes ControllerState, reads every output
#     --operator NAME       a client with the operator role: may also write SceneCommand
#     --expired NAME        a client whose certificate expired (tests: refused)
#     --foreign NAME        a client of another CA: OUTDIR/<name> holds its own ca.pem,
#                           governance.p7s and permissions.p7s, all from that CA (tests: refused)
#
# Run a tool with it: TELEGRASP_SECURITY_DIR=OUTDIR TELEGRASP_IDENTITY=<name> and --profile secure
# (telegrasp-server also takes --security OUTDIR --identity NAME). The governance encrypts
# (AES-GCM) the data of the topics that carry people's motion (ControllerState, HandSkeleton,
# GraspState, ContactSet, GraspEvent, SceneState) and signs (GMAC) the others' submessages; discovery and
# liveliness are encrypted; unauthenticated participants are not admitted. Certificates are
# EC prime256v1, valid --days (default 3650) days. Existing files in OUTDIR are replaced.
set -euo pipefail

usage() { sed -n '2,25p' "$0" | sed 's/^# \{0,1\}//'; }
fail() { echo "make-certs.sh: $*" >&2; echo "(see make-certs.sh --help)" >&2; exit 2; }

out="" days=3650
clients=() operators=() expired=() foreign=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --operator) [[ $# -ge 2 ]] || fail "--operator needs a name"; operators+=("$2"); shift 2 ;;
    --expired) [[ $# -ge 2 ]] || fail "--expired needs a name"; expired+=("$2"); shift 2 ;;
    --foreign) [[ $# -ge 2 ]] || fail "--foreign needs a name"; foreign+=("$2"); shift 2 ;;
    --days) [[ $# -ge 2 && "$2" =~ ^[1-9][0-9]*$ ]] || fail "--days expects a whole number >= 1, got '${2:-}'"
            days="$2"; shift 2 ;;
    -*) fail "unknown option '$1'" ;;
    *) if [[ -z "$out" ]]; then out="$1"; else clients+=("$1"); fi; shift ;;
  esac
done
[[ -n "$out" ]] || fail "needs an output folder (OUTDIR)"
command -v openssl >/dev/null || { echo "make-certs.sh: openssl not found (apt-get install openssl)" >&2; exit 1; }
for n in server "${clients[@]}" "${operators[@]}" "${expired[@]}" "${foreign[@]}"; do
  [[ "$n" =~ ^[A-Za-z0-9_.-]+$ && "$n" != "." && "$n" != ".." ]] ||
    fail "identity names are letters, digits, '_', '.' and '-'; got '$n'"
done
mkdir -p "$out"
out="$(cd "$out" && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

topics_out=(HandSkeleton GraspState ContactSet GraspEvent SceneState ServerStatus ObjectGeometry ClientNotice SceneDirectory)
# Topics whose samples are people's motion (or follow it): encrypted; the rest signed.
encrypted=(ControllerState HandSkeleton GraspState ContactSet GraspEvent SceneState)

# make_ca DIR CN: a self-signed CA (DIR/ca.pem, DIR/ca.key) and the openssl ca database beside.
make_ca() {
  local dir="$1" cn="$2"
  mkdir -p "$dir"
  openssl ecparam -name prime256v1 -genkey -noout -out "$dir/ca.key" 2>/dev/null
  openssl req -new -x509 -sha256 -key "$dir/ca.key" -out "$dir/ca.pem" -days "$days" \
    -subj "/O=telegrasp/CN=$cn" -addext "basicConstraints=critical,CA:TRUE" \
    -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature"
  chmod 600 "$dir/ca.key"
}

# ca_conf CADIR: an `openssl ca` configuration (it alone can set a start and end date).
ca_conf() {
  local ca="$1" db="$tmp/db$RANDOM$RANDOM"
  mkdir -p "$db"; : >"$db/index.txt"; openssl rand -hex 16 >"$db/serial"
  cat >"$db/ca.cnf" <<CNF
[ ca ]
default_ca = telegrasp
[ telegrasp ]
dir = $db
database = $db/index.txt
serial = $db/serial
new_certs_dir = $db
certificate = $ca/ca.pem
private_key = $ca/ca.key
default_md = sha256
policy = anything
unique_subject = no
copy_extensions = none
x509_extensions = identity
[ anything ]
organizationName = optional
commonName = supplied
[ identity ]
basicConstraints = critical,CA:FALSE
keyUsage = critical,digitalSignature,keyAgreement
CNF
  echo "$db/ca.cnf"
}

# sign CADIR FILE.xml FILE.p7s: S/MIME signature by the CA, as Fast DDS reads governance and
# permissions documents.
sign() { openssl smime -sign -in "$2" -text -out "$3" -signer "$1/ca.pem" -inkey "$1/ca.key"; }

# identity CADIR NAME ROLE [expired]: key, certificate signed by CADIR and permissions for ROLE
# (client | operator | server) in $out/NAME.
identity() {
  local ca="$1" name="$2" role="$3" when="${4:-}" dir="$out/$2"
  mkdir -p "$dir"
  openssl ecparam -name prime256v1 -genkey -noout -out "$dir/key.pem" 2>/dev/null
  chmod 600 "$dir/key.pem"
  openssl req -new -key "$dir/key.pem" -out "$tmp/$name.csr" -subj "/O=telegrasp/CN=$name"
  local conf; conf="$(ca_conf "$ca")"
  local dates=(-days "$days")
  [[ "$when" == expired ]] && dates=(-startdate 20200101000000Z -enddate 20200102000000Z)
  openssl ca -batch -notext -config "$conf" "${dates[@]}" -in "$tmp/$name.csr" -out "$dir/cert.pem" 2>/dev/null ||
    { echo "make-certs.sh: openssl could not sign the certificate of '$name'" >&2; exit 1; }
  local subject; subject="$(openssl x509 -in "$dir/cert.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')"
  local publish=() subscribe=()
  # Every scene (DDS partition telegrasp/scene/<name>) and the scene directory's partition: a
  # rule without partitions would cover only the default, empty partition.
  local partitions='<partitions><partition>telegrasp/scene/*</partition><partition>telegrasp/directory</partition></partitions>'
  case "$role" in
    server) publish=("${topics_out[@]}"); subscribe=(ControllerState SceneCommand SceneDirectory) ;;
    operator) publish=(ControllerState SceneCommand); subscribe=("${topics_out[@]}") ;;
    client) publish=(ControllerState); subscribe=("${topics_out[@]}") ;;
  esac
  {
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo "<!-- telegrasp permissions of '$name' (role $role), made by deploy/security/make-certs.sh -->"
    echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">'
    echo '  <permissions>'
    echo "    <grant name=\"$name\">"
    echo "      <subject_name>$subject</subject_name>"
    echo '      <validity><not_before>2020-01-01T00:00:00</not_before><not_after>2100-01-01T00:00:00</not_after></validity>'
    echo '      <allow_rule>'
    echo '        <domains><id_range><min>0</min><max>232</max></id_range></domains>'
    echo '        <publish><topics>'
    for t in "${publish[@]}"; do echo "          <topic>telegrasp/$t</topic>"; done
    echo "        </topics>$partitions</publish>"
    echo '        <subscribe><topics>'
    for t in "${subscribe[@]}"; do echo "          <topic>telegrasp/$t</topic>"; done
    echo "        </topics>$partitions</subscribe>"
    echo '      </allow_rule>'
    echo '      <default>DENY</default>'
    echo '    </grant>'
    echo '  </permissions>'
    echo '</dds>'
  } >"$dir/permissions.xml"
  sign "$ca" "$dir/permissions.xml" "$dir/permissions.p7s"
}

# governance CADIR OUT: the domain rules, signed.
governance() {
  local ca="$1" dir="$2"
  {
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo '<!-- telegrasp governance, made by deploy/security/make-certs.sh -->'
    echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">'
    echo '  <domain_access_rules>'
    echo '    <domain_rule>'
    echo '      <domains><id_range><min>0</min><max>232</max></id_range></domains>'
    echo '      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>'
    echo '      <enable_join_access_control>true</enable_join_access_control>'
    echo '      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>'
    echo '      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>'
    echo '      <rtps_protection_kind>NONE</rtps_protection_kind>'
    echo '      <topic_access_rules>'
    for t in ControllerState SceneCommand "${topics_out[@]}"; do
      # Fast DDS 2.9 cannot decode SIGN data protection: the others sign whole submessages.
      local meta=SIGN data=NONE
      [[ " ${encrypted[*]} " == *" $t "* ]] && meta=NONE data=ENCRYPT
      echo '        <topic_rule>'
      echo "          <topic_expression>telegrasp/$t</topic_expression>"
      echo '          <enable_discovery_protection>true</enable_discovery_protection>'
      echo '          <enable_liveliness_protection>true</enable_liveliness_protection>'
      echo '          <enable_read_access_control>true</enable_read_access_control>'
      echo '          <enable_write_access_control>true</enable_write_access_control>'
      echo "          <metadata_protection_kind>$meta</metadata_protection_kind>"
      echo "          <data_protection_kind>$data</data_protection_kind>"
      echo '        </topic_rule>'
    done
    echo '      </topic_access_rules>'
    echo '    </domain_rule>'
    echo '  </domain_access_rules>'
    echo '</dds>'
  } >"$dir/governance.xml"
  sign "$ca" "$dir/governance.xml" "$dir/governance.p7s"
}

make_ca "$out" "telegrasp CA"
governance "$out" "$out"
identity "$out" server server
for n in "${clients[@]}"; do identity "$out" "$n" client; done
for n in "${operators[@]}"; do identity "$out" "$n" operator; done
for n in "${expired[@]}"; do identity "$out" "$n" client expired; done
for n in "${foreign[@]}"; do
  # Another CA's complete set, in the identity's own folder: what an outsider could make.
  make_ca "$tmp/foreign-$n" "foreign CA"
  identity "$tmp/foreign-$n" "$n" operator
  cp "$tmp/foreign-$n/ca.pem" "$out/$n/ca.pem"
  governance "$tmp/foreign-$n" "$out/$n"
done
echo "make-certs.sh: CA, governance and identities server ${clients[*]} ${operators[*]:+(operators: ${operators[*]})}${expired[*]:+ (expired: ${expired[*]})}${foreign[*]:+ (foreign CA: ${foreign[*]})} in $out" >&2
