#!/usr/bin/env python3
"""tools/pki without DDS: what it writes (checked with openssl, as Fast DDS checks it) and how it
refuses what it cannot do. Usage: pki_test.py PATH_TO_TOOLS_PKI"""

import os
import re
import stat
import subprocess
import sys
import tempfile
import unittest

PKI = None


def openssl(*argv):
    return subprocess.run(["openssl", *argv], capture_output=True, text=True)


class Pki(unittest.TestCase):
    def setUp(self):
        self.work = tempfile.TemporaryDirectory(prefix="teejet-pki-")
        self.site = os.path.join(self.work.name, "site")

    def tearDown(self):
        self.work.cleanup()

    def pki(self, *argv):
        return subprocess.run([PKI, *argv], capture_output=True, text=True)

    def ok(self, *argv):
        result = self.pki(*argv)
        self.assertEqual(result.returncode, 0, result.stderr)
        return result.stdout

    def refused(self, expected_message, *argv):
        result = self.pki(*argv)
        self.assertEqual(result.returncode, 1, result.stdout)
        self.assertIn(expected_message, result.stderr)

    def path(self, *parts):
        return os.path.join(self.site, *parts)

    def read(self, *parts):
        with open(self.path(*parts)) as text:
            return text.read()

    def init(self):
        self.ok("init", self.site, "--site", "farm", "--days", "10")

    def verify_signed(self, name):
        """The document as Fast DDS reads it: S/MIME verified against the permissions CA."""
        result = openssl("smime", "-verify", "-text", "-in", self.path(name), "-CAfile",
                         self.path("permissions_ca.pem"))
        self.assertEqual(result.returncode, 0, result.stderr)
        return result.stdout

    def test_init_makes_two_p256_cas_private_keys_and_signed_governance(self):
        self.init()
        for which in ("identity", "permissions"):
            text = openssl("x509", "-in", self.path(f"{which}_ca.pem"), "-noout", "-text").stdout
            self.assertIn("NIST CURVE: P-256", text)
            self.assertIn("CA:TRUE", text)
            key = os.stat(self.path("private", f"{which}_ca.key"))
            self.assertEqual(stat.S_IMODE(key.st_mode), 0o600)
        self.assertEqual(stat.S_IMODE(os.stat(self.path("private")).st_mode), 0o700)
        governance = self.verify_signed("governance.p7s")
        self.assertIn("<allow_unauthenticated_participants>false<", governance)
        self.assertIn("<min>0</min><max>232</max>", governance)
        self.assertRegex(governance, r"teejet/valve/command</topic_expression>(.|\n)*"
                                     r"<data_protection_kind>ENCRYPT<")
        self.assertNotIn("@DOMAINS@", governance)

    def test_issue_writes_a_cn_first_grant_per_participant_with_its_role(self):
        self.init()
        out = self.ok("issue", self.site, "commander", "bench-1")
        self.assertIn("bench-1: commander, CN=bench-1,OU=commander,O=farm", out)
        self.ok("issue", self.site, "observer", "dash")
        self.ok("issue", self.site, "gateway", "gw")
        key = os.stat(self.path("participants", "bench-1", "key.pem"))
        self.assertEqual(stat.S_IMODE(key.st_mode), 0o600)
        chain = openssl("verify", "-CAfile", self.path("identity_ca.pem"),
                        self.path("participants", "bench-1", "cert.pem"))
        self.assertEqual(chain.returncode, 0, chain.stderr)
        permissions = self.verify_signed("permissions.p7s")
        grants = dict(re.findall(r'<grant name="([^"]+)">\s*<subject_name>([^<]+)<', permissions))
        self.assertEqual(grants, {"bench-1": "CN=bench-1,OU=commander,O=farm",
                                  "dash": "CN=dash,OU=observer,O=farm",
                                  "gw": "CN=gw,OU=gateway,O=farm"})
        observer = permissions.split('<grant name="dash">')[1].split("</grant>")[0]
        # An observer writes nothing but its own event watchdog's beat (docs/topics.md).
        published = re.findall(r"<publish>([\s\S]*?)</publish>", observer)
        self.assertEqual([re.findall(r"<topic>([^<]*)</topic>", p) for p in published],
                         [["teejet/event_watchdog"]])
        self.assertNotIn("teejet/valve/command<", observer)
        self.assertIn("<default>DENY</default>", observer)
        # Fast DDS reads grant times in local time: a day's margin each side of the certificate.
        start = openssl("x509", "-in", self.path("participants", "dash", "cert.pem"), "-noout",
                        "-startdate").stdout.strip().split("=")[1]
        day_before = subprocess.run(["date", "-u", "-d", f"{start} - 1 day",
                                     "+%Y-%m-%dT%H:%M:%S"], capture_output=True, text=True)
        self.assertIn(f"<not_before>{day_before.stdout.strip()}</not_before>", observer)
        gateway = permissions.split('<grant name="gw">')[1].split("</grant>")[0]
        self.assertIn("<subscribe>\n          <topics>\n            <topic>teejet/valve/command<",
                      gateway)

    def test_expired_certificate_ended_in_2020(self):
        self.init()
        self.ok("issue", self.site, "commander", "late", "--expired")
        end = openssl("x509", "-in", self.path("participants", "late", "cert.pem"), "-noout",
                      "-enddate").stdout.strip()
        self.assertEqual(end, "notAfter=Feb  1 00:00:00 2020 GMT")
        self.assertRegex(self.ok("list", self.site), r"late +commander +expired")

    def test_replace_rotates_the_key_and_revokes_the_old_certificate(self):
        self.init()
        self.ok("issue", self.site, "commander", "bench")
        old = openssl("x509", "-in", self.path("participants", "bench", "cert.pem"), "-noout",
                      "-serial").stdout.strip().split("=")[1]
        old_key = self.read("participants", "bench", "key.pem")
        self.ok("issue", self.site, "commander", "bench", "--replace", "--days", "5")
        self.assertNotEqual(self.read("participants", "bench", "key.pem"), old_key)
        crl = openssl("crl", "-in", self.path("crl.pem"), "-noout", "-text").stdout
        self.assertIn(f"Serial Number: {old}", crl)
        self.assertIn('<grant name="bench">', self.verify_signed("permissions.p7s"))

    def test_revoke_removes_the_grant_and_lists_the_certificate(self):
        self.init()
        self.ok("issue", self.site, "commander", "bench")
        self.ok("issue", self.site, "observer", "dash")
        serial = openssl("x509", "-in", self.path("participants", "bench", "cert.pem"), "-noout",
                         "-serial").stdout.strip().split("=")[1]
        self.ok("revoke", self.site, "bench")
        permissions = self.verify_signed("permissions.p7s")
        self.assertNotIn('<grant name="bench">', permissions)
        self.assertIn('<grant name="dash">', permissions)
        crl = openssl("crl", "-in", self.path("crl.pem"), "-noout", "-text",
                      ).stdout
        self.assertIn(f"Serial Number: {serial}", crl)
        self.refused("participant 'bench' is revoked already", "revoke", self.site, "bench")
        self.refused("participant 'bench' is revoked", "profile", self.site, "bench", "--base",
                     self.path("site.conf"))

    def test_profile_adds_the_security_properties_to_the_default_participant(self):
        self.init()
        self.ok("issue", self.site, "gateway", "gw")
        base = os.path.join(os.path.dirname(PKI), "..", "config", "fastdds-loopback.xml")
        self.ok("profile", self.site, "gw", "--base", base, "--files-at", "/etc/teejet/security")
        profile = self.read("gw.xml")
        self.assertIn("<value>file:///etc/teejet/security/participants/gw/key.pem</value>",
                      profile)
        self.assertIn("<value>builtin.AES-GCM-GMAC</value>", profile)
        # The properties sit inside the default participant's <rtps>, the transports stay.
        self.assertRegex(profile, r'is_default_profile="true">\s*<rtps>\s*<propertiesPolicy>')
        self.assertIn("<transport_id>teejet_loopback_udp</transport_id>", profile)
        self.assertEqual(subprocess.run(["python3", "-c", "import sys, xml.dom.minidom as m; "
                                         "m.parse(sys.argv[1])", self.path("gw.xml")]).returncode,
                         0)

    def test_clear_errors(self):
        self.refused("is not a site made by 'tools/pki init'", "issue", self.site, "observer", "x")
        self.refused("--site NAME is required", "init", self.site)
        self.refused("--days must be a whole number of days", "init", self.site, "--site", "f",
                     "--days", "-3")
        self.init()
        self.refused("exists and is not empty", "init", self.site, "--site", "farm")
        self.refused("unknown role 'admin' (roles: commander gateway observer recorder)", "issue",
                     self.site, "admin", "x")
        self.refused("participant name 'a/b' must be", "issue", self.site, "observer", "a/b")
        self.ok("issue", self.site, "observer", "dash")
        self.refused("participant 'dash' exists already (role observer)", "issue", self.site,
                     "commander", "dash")
        self.refused("--replace: there is no participant 'nobody'", "issue", self.site,
                     "observer", "nobody", "--replace")
        self.refused("--base FILE is required", "profile", self.site, "dash")
        self.refused("base profile '/nonexistent.xml' does not exist", "profile", self.site,
                     "dash", "--base", "/nonexistent.xml")
        self.refused("has no <participant> profile", "profile", self.site, "dash", "--base",
                     self.path("site.conf"))
        server = os.path.join(self.work.name, "server.xml")
        with open(server, "w") as out:
            out.write("<dds><profiles><participant profile_name='s'><rtps><builtin>"
                      "<discovery_config><discoveryProtocol>SERVER</discoveryProtocol>"
                      "</discovery_config></builtin></rtps></participant></profiles></dds>\n")
        self.refused("uses a Discovery Server; Fast DDS 2.9 cannot combine it with security",
                     "profile", self.site, "dash", "--base", server)
        self.refused("no participant 'ghost'", "profile", self.site, "ghost", "--base",
                     self.path("site.conf"))
        os.rename(self.path("private", "permissions_ca.key"), self.path("private", "moved.key"))
        self.refused("has no permissions CA", "issue", self.site, "observer", "other")
        self.refused("unknown command 'destroy'", "destroy", self.site)


if __name__ == "__main__":
    PKI = os.path.abspath(sys.argv.pop(1))
    unittest.main(verbosity=2)
