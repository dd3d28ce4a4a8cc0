// TLS and mutual TLS between real processes: a master that requires client certificates renders a job
// for a worker and a client that present them, and refuses connections that do not.
#include <gtest/gtest.h>

#include "farm/harness.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

// A throwaway CA and two certificates it signs, made with the openssl command line.
void makeCertificates(const std::string &dir) {
    writeFile(dir, "san.ext", "subjectAltName=IP:127.0.0.1\n");
    const std::string key = " -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";
    const std::vector<std::string> steps = {
        "req -x509" + key + " -keyout ca.key -out ca.pem -days 1 -subj /CN=pathfarm-test-ca",
        "req" + key + " -keyout server.key -out server.csr -subj /CN=127.0.0.1",
        "x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out server.pem -days 1 -extfile san.ext",
        "req" + key + " -keyout client.key -out client.csr -subj /CN=pathfarm-test-client",
        "x509 -req -in client.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out client.pem -days 1",
    };
    for (const std::string &step : steps) {
        const auto r = runCommand("cd " + dir + " && openssl " + step);
        ASSERT_EQ(r.exitCode, 0) << step << "\n" << r.output;
    }
}

TEST(FarmTls, MutualTlsRendersAndRefusesStrangers) {
    Farm farm("tls");
    makeCertificates(farm.dir());
    const std::string d = farm.dir() + "/";
    farm.useTls({d + "client.pem", d + "client.key", d + "ca.pem"});
    farm.startMaster({"--tls-cert", d + "server.pem", "--tls-key", d + "server.key", "--tls-client-ca", d + "ca.pem"});
    farm.startWorker(1, {"--tls-ca", d + "ca.pem", "--tls-cert", d + "client.pem", "--tls-key", d + "client.key"});

    const std::string scene = writeTestScene(farm.dir() + "/scene", 16, 8);
    const std::string tls = " --tls-ca " + d + "ca.pem --tls-cert " + d + "client.pem --tls-key " + d + "client.key";
    const auto [code, output] = farm.cli("submit " + scene + " --spp 16 --wait -o " + d + "out.exr" + tls);
    ASSERT_EQ(code, 0) << output << farm.master().log();
    ASSERT_EQ(farm.cli("render " + scene + " -q --spp 16 -o " + d + "ref.exr").first, 0);
    EXPECT_TRUE(sameBits(d + "ref.exr", d + "out.exr"));

    // Without a client certificate, or without TLS at all, nothing gets through.
    const auto [c1, noCert] = farm.cli("status --tls-ca " + d + "ca.pem");
    EXPECT_NE(c1, 0) << noCert;
    const auto [c2, plain] = farm.cli("status");
    EXPECT_NE(c2, 0) << plain;
    EXPECT_TRUE(farm.master().running());
}

}  // namespace
}  // namespace pf::test::farm
