# Sourced by the tests of the secured bus: security_yaml DIR prints the config's `dds.security` block (indented
# for a `dds:` section at the top level) for the participant folder DIR that make_security.sh wrote.
security_yaml() {
    cat <<YAML
  security:
    enabled: true
    identity_ca: $1/identity_ca.cert.pem
    certificate: $1/cert.pem
    private_key: $1/key.pem
    permissions_ca: $1/permissions_ca.cert.pem
    governance: $1/governance.p7s
    permissions: $1/permissions.p7s
YAML
}
