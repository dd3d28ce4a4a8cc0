#!/usr/bin/env python3
"""Checks deploy/compose.yaml and deploy/k8s/*.yaml without a cluster (scripts/container-test.sh runs it).

A YAML parse alone would pass a manifest whose Service selects no pod or whose probe names no port, so
this checks what ties the objects together: selectors against pod labels, probe and Service ports against
container ports, Secret keys and claims against what exists, the worker's CPU request = limit = --threads,
the master's single replica with Recreate, and the compose file's health-gated start and CPU limits.
Exit status 1 and one line per problem when anything is wrong.
"""
import pathlib
import sys

import yaml

DEPLOY = pathlib.Path(__file__).resolve().parent
problems = []


def check(cond, what):
    if not cond:
        problems.append(what)


def arg_value(args, flag):
    for a in args:
        if a.startswith(flag + "="):
            return a.split("=", 1)[1]
    return None


def cpus(quantity):
    q = str(quantity)
    return float(q[:-1]) / 1000 if q.endswith("m") else float(q)


def check_k8s():
    objects = {}
    for path in sorted((DEPLOY / "k8s").glob("*.yaml")):
        for doc in yaml.safe_load_all(path.read_text()):
            if doc is None or doc.get("kind") == "Kustomization":
                continue
            for field in ("apiVersion", "kind", "metadata"):
                check(field in doc, f"{path.name}: an object without {field}")
            objects[(doc["kind"], doc["metadata"]["name"])] = (path.name, doc)
    kustomization = yaml.safe_load((DEPLOY / "k8s" / "kustomization.yaml").read_text())
    for res in kustomization["resources"]:
        check((DEPLOY / "k8s" / res).exists(), f"kustomization.yaml: missing resource {res}")

    secret = objects.get(("Secret", "pathfarm-tokens"))
    check(secret is not None, "no example Secret pathfarm-tokens")
    secret_keys = set(secret[1].get("stringData", {})) if secret else set()
    check(secret_keys == {"client_token", "worker_token"}, f"Secret keys {secret_keys}")
    if secret:
        values = secret[1]["stringData"]
        check(values["client_token"] != values["worker_token"], "the example tokens must differ")

    deployments = {name: doc for (kind, name), (_, doc) in objects.items() if kind == "Deployment"}
    for name, dep in deployments.items():
        spec, pod = dep["spec"], dep["spec"]["template"]
        labels = pod["metadata"]["labels"]
        check(all(labels.get(k) == v for k, v in spec["selector"]["matchLabels"].items()),
              f"{name}: selector does not match the pod labels")
        volumes = {v["name"]: v for v in pod["spec"].get("volumes", [])}
        check(pod["spec"]["securityContext"].get("runAsNonRoot") is True, f"{name}: not runAsNonRoot")
        for c in pod["spec"]["containers"]:
            ports = {p["name"]: p["containerPort"] for p in c.get("ports", [])}
            for probe in ("readinessProbe", "livenessProbe"):
                p = c.get(probe)
                check(p is not None, f"{name}: no {probe}")
                if p is None:
                    continue
                port = (p.get("httpGet") or p.get("grpc") or p.get("tcpSocket") or {}).get("port")
                check(port in ports or port in ports.values(), f"{name}: {probe} port {port} is not a container port")
            for m in c.get("volumeMounts", []):
                check(m["name"] in volumes, f"{name}: mount of unknown volume {m['name']}")
            args = c.get("args", [])
            for flag in ("--token-file", "--worker-token-file"):
                value = arg_value(args, flag)
                if value:
                    key = value.rsplit("/", 1)[1]
                    check(key in secret_keys, f"{name}: {flag} names {key}, not a key of the Secret")
        for v in volumes.values():
            if "persistentVolumeClaim" in v:
                claim = v["persistentVolumeClaim"]["claimName"]
                check(("PersistentVolumeClaim", claim) in objects, f"{name}: unknown claim {claim}")
            if "secret" in v:
                check(v["secret"]["secretName"] == "pathfarm-tokens", f"{name}: unknown Secret")

    master = deployments.get("pathfarm-master")
    check(master is not None, "no Deployment pathfarm-master")
    if master:
        check(master["spec"]["replicas"] == 1, "the master must have one replica (one SQLite store)")
        check(master["spec"]["strategy"]["type"] == "Recreate", "the master must be replaced, not rolled")
        c = master["spec"]["template"]["spec"]["containers"][0]
        check(c["args"][0] == "pathfarm-master", "the master Deployment does not run pathfarm-master")
        service = objects.get(("Service", "pathfarm-master"))
        check(service is not None, "no Service pathfarm-master")
        if service:
            s = service[1]["spec"]
            pod_labels = master["spec"]["template"]["metadata"]["labels"]
            check(all(pod_labels.get(k) == v for k, v in s["selector"].items()), "the Service selects no master pod")
            names = {p["name"] for p in c["ports"]}
            check({p["targetPort"] for p in s["ports"]} == names == {"grpc", "http"},
                  "the Service must expose the master's grpc and http ports")

    worker = deployments.get("pathfarm-worker")
    check(worker is not None, "no Deployment pathfarm-worker")
    if worker:
        c = worker["spec"]["template"]["spec"]["containers"][0]
        res = c["resources"]
        check(res["requests"]["cpu"] == res["limits"]["cpu"], "worker CPU request != limit")
        threads = arg_value(c["args"], "--threads")
        check(threads is not None and float(threads) == cpus(res["limits"]["cpu"]),
              f"worker --threads {threads} != CPU limit {res['limits']['cpu']}")
        check(arg_value(c["args"], "--master") == "pathfarm-master:7700", "workers do not address the Service")
        health = arg_value(c["args"], "--health-listen")
        check(health is not None and health.endswith(":7701") and not health.startswith("127."),
              "the worker's health service must listen on the pod address, port 7701")


def check_compose():
    compose = yaml.safe_load((DEPLOY / "compose.yaml").read_text())
    services = compose["services"]
    check(set(services) == {"master", "worker"}, f"compose services {set(services)}")
    for name, s in services.items():
        check("healthcheck" in s, f"compose {name}: no healthcheck")
        check("cpus" in s.get("deploy", {}).get("resources", {}).get("limits", {}), f"compose {name}: no CPU limit")
        for secret in s.get("secrets", []):
            check(secret in compose["secrets"], f"compose {name}: unknown secret {secret}")
            check(any(a.endswith("/run/secrets/" + secret) for a in s["command"]), f"compose {name}: {secret} unused")
    worker, master = services["worker"], services["master"]
    check(worker["depends_on"]["master"]["condition"] == "service_healthy", "workers must wait for a healthy master")
    check(arg_value(worker["command"], "--master") == "master:7700", "compose workers do not address the master")
    check(any(v.endswith(":/var/lib/pathfarm") for v in master["volumes"]), "the master's data is not on a volume")
    check(worker["healthcheck"]["test"].endswith(" " + worker["environment"]["PATHFARM_HEALTH_ADDR"])
          and arg_value(worker["command"], "--health-listen").endswith(":7701"),
          "the worker's health check does not reach its --health-listen port")


check_k8s()
check_compose()
for p in problems:
    print("check-manifests:", p, file=sys.stderr)
if problems:
    sys.exit(1)
print("check-manifests: deploy/compose.yaml and deploy/k8s/*.yaml are consistent")
