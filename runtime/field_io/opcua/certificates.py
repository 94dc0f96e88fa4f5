"""The certificates of OPC UA: the resource's own, made at the first start and kept in its
state folder, and the clients' it trusts.

The folder (`<state>/opcua/`) holds `certificate.der` and `private-key.pem` (owner-only),
the client's `client/client-certificate.der` and `client/client-private-key.pem`,
and `pki/trusted/` and `pki/rejected/` with one DER file of a client certificate each,
named by its SHA-1 thumbprint (as OPC UA tools show it). A client whose certificate is
in neither is refused and its certificate lands in `rejected/`; moving the file to
`trusted/` lets it in at its next attempt, without a restart.
"""

from __future__ import annotations

import datetime
import hashlib
import ipaddress
import threading
from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import rsa
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from runtime.contract.private_files import write_private

VALID_DAYS = 3650
KEY_BITS = 2048  # what Basic256Sha256 asks for
MAX_REJECTED = 100  # certificates kept in rejected/: a flood of new ones fills no disk


@dataclass(frozen=True)
class ApplicationCertificate:
    certificate: Path  # DER
    private_key: Path  # PEM, owner-only
    thumbprint: str  # SHA-1, upper-case hex
    created: bool  # made just now (none usable was there)


SERVER_FILES = ("certificate.der", "private-key.pem")
SERVER_USAGES = (ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH)
_making = threading.Lock()  # the drivers of one process make one certificate per folder


def application_certificate(
    folder: Path,
    name: str,
    uri: str,
    hosts: tuple[str, ...],
    now: datetime.datetime,
    files: tuple[str, str] = SERVER_FILES,
    usages: tuple[x509.ObjectIdentifier, ...] = SERVER_USAGES,
) -> ApplicationCertificate:
    """The application certificate kept in `folder` (its `files`: certificate, key), or a
    new one made there for an application `name` with the application URI `uri` (which
    peers compare with the certificate's) reachable at `hosts`, when the one kept is
    missing, of another URI, expiring within a day, or not of its key."""
    certificate, key = folder / files[0], folder / files[1]
    with _making:
        found = _usable(certificate, key, uri, now)
        if found is not None:
            return ApplicationCertificate(certificate, key, thumbprint(found), False)
        folder.mkdir(parents=True, exist_ok=True)
        private = rsa.generate_private_key(public_exponent=65537, key_size=KEY_BITS)
        made = _certificate(private, name, uri, hosts, now, usages)
        write_private(
            key,
            private.private_bytes(
                serialization.Encoding.PEM,
                serialization.PrivateFormat.TraditionalOpenSSL,
                serialization.NoEncryption(),
            ),
        )
        certificate.write_bytes(made.public_bytes(serialization.Encoding.DER))
    return ApplicationCertificate(certificate, key, thumbprint(made), True)


def thumbprint(certificate: x509.Certificate) -> str:
    return hashlib.sha1(certificate.public_bytes(serialization.Encoding.DER)).hexdigest().upper()


def _usable(
    certificate: Path, key: Path, uri: str, now: datetime.datetime
) -> x509.Certificate | None:
    try:
        found = x509.load_der_x509_certificate(certificate.read_bytes())
        private = serialization.load_pem_private_key(key.read_bytes(), password=None)
        names = found.extensions.get_extension_for_class(x509.SubjectAlternativeName)
    except (OSError, ValueError, TypeError, x509.ExtensionNotFound):
        return None
    usable = (
        uri in names.value.get_values_for_type(x509.UniformResourceIdentifier)
        and found.not_valid_after_utc > now + datetime.timedelta(days=1)
        and found.public_key() == private.public_key()
    )
    return found if usable else None


def _certificate(
    key: rsa.RSAPrivateKey,
    name: str,
    uri: str,
    hosts: tuple[str, ...],
    now: datetime.datetime,
    usages: tuple[x509.ObjectIdentifier, ...],
) -> x509.Certificate:
    subject = x509.Name(
        [
            x509.NameAttribute(NameOID.COMMON_NAME, name),
            x509.NameAttribute(NameOID.ORGANIZATION_NAME, "padt"),
        ]
    )
    alternative: list[x509.GeneralName] = [x509.UniformResourceIdentifier(uri)]
    for host in hosts:
        try:
            alternative.append(x509.IPAddress(ipaddress.ip_address(host)))
        except ValueError:
            alternative.append(x509.DNSName(host))
    return (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(subject)  # self-signed, as OPC UA applications' are
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(days=1))
        .not_valid_after(now + datetime.timedelta(days=VALID_DAYS))
        .add_extension(x509.SubjectAlternativeName(alternative), critical=False)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=True,
                content_commitment=True,
                key_encipherment=True,
                data_encipherment=True,
                key_agreement=False,
                key_cert_sign=False,
                crl_sign=False,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.ExtendedKeyUsage(list(usages)), critical=False)
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
        .sign(key, hashes.SHA256())
    )


class TrustList:
    """The client certificates let in (`trusted/`) and those refused (`rejected/`)."""

    def __init__(self, pki: Path, trust_unknown: bool) -> None:
        self.trusted, self.rejected = pki / "trusted", pki / "rejected"
        self.trusted.mkdir(parents=True, exist_ok=True)
        self.rejected.mkdir(parents=True, exist_ok=True)
        self._trust_unknown = trust_unknown

    def admits(self, certificate: x509.Certificate) -> bool:
        """Whether a client with this certificate is let in; one that is not lands in
        `rejected/` (once, and only while it holds fewer than MAX_REJECTED)."""
        name = f"{thumbprint(certificate)}.der"
        if self._trust_unknown or (self.trusted / name).is_file():
            return True
        rejected = self.rejected / name
        if not rejected.exists() and self.listed()[1] < MAX_REJECTED:
            rejected.write_bytes(certificate.public_bytes(serialization.Encoding.DER))
        return False

    def listed(self) -> tuple[int, int]:
        """How many certificates are trusted, and how many rejected."""
        return len(list(self.trusted.glob("*.der"))), len(list(self.rejected.glob("*.der")))
