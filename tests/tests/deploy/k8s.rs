//! deploy/k8s/: the StatefulSet of servers, its Service, the zenohd Deployment, the ConfigMap and the Secrets'
//! templates.

use std::collections::{BTreeMap, BTreeSet};

use serde_json::Value;

use crate::dockerfile::Dockerfile;
use crate::zenohd::{check_router_args, router_listen_port};
use crate::{
    SET_DIR, deploy, dmp_server_args, port_of, read, set_files, set_paths_in, strings, yaml_documents,
};

/// Every object of deploy/k8s/, by `Kind/name`.
fn objects() -> BTreeMap<String, Value> {
    let mut out = BTreeMap::new();
    let kustomization = yaml_documents(&deploy().join("k8s/kustomization.yaml")).remove(0);
    let mut files = strings(&kustomization["resources"], "kustomization resources");
    files.push("secrets.template.yaml".into());
    for file in files {
        for doc in yaml_documents(&deploy().join("k8s").join(&file)) {
            let kind = doc["kind"].as_str().unwrap_or_else(|| panic!("{file}: an object without a kind"));
            let name =
                doc["metadata"]["name"].as_str().unwrap_or_else(|| panic!("{file}: {kind} without a name"));
            assert!(doc["apiVersion"].is_string(), "{file}: {kind}/{name} has no apiVersion");
            out.insert(format!("{kind}/{name}"), doc);
        }
    }
    out
}

/// The keys of a Secret (template) or ConfigMap.
fn keys(object: &Value, field: &str) -> BTreeSet<String> {
    object[field].as_object().unwrap().keys().cloned().collect()
}

/// The container's named ports.
fn named_ports(container: &Value) -> BTreeMap<String, u16> {
    container["ports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["name"].as_str().unwrap().to_owned(), p["containerPort"].as_u64().unwrap() as u16))
        .collect()
}

/// The mount path of the pod's volume that comes from `source` (e.g. `secret`) named `name`.
fn mount_of(pod: &Value, container: &Value, source: &str, name: &str) -> String {
    let volume = pod["volumes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| {
            let s = &v[source];
            s["secretName"].as_str() == Some(name) || s["name"].as_str() == Some(name)
        })
        .unwrap_or_else(|| panic!("no {source} volume of {name}"));
    let mount = container["volumeMounts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == volume["name"])
        .unwrap_or_else(|| panic!("the {source} {name} is not mounted"));
    mount["mountPath"].as_str().unwrap().to_owned()
}

#[test]
fn the_kubernetes_files_parse_and_agree_with_the_image_the_server_and_each_other() {
    let docker = Dockerfile::load();
    let (grpc_port, metrics_port) = docker.grpc_and_metrics_ports();
    let objects = objects();
    let o = |key: &str| {
        objects.get(key).unwrap_or_else(|| panic!("no {key} in deploy/k8s: {:?}", objects.keys()))
    };
    let server_set = keys(o("Secret/dmp-server-set"), "stringData");
    let router_set = keys(o("Secret/zenohd-set"), "stringData");
    assert!(
        !server_set.contains("ca.key") && !router_set.contains("ca.key"),
        "the CA's key stays off the cluster"
    );
    let statefulset = o("StatefulSet/dmp-server");
    let replicas = statefulset["spec"]["replicas"].as_u64().unwrap();
    // The set the template's comment makes: a cell per pod, the pods' and the router's names.
    let cells: Vec<String> = (0..replicas).map(|i| format!("dmp-server-{i}")).collect();
    let cells: Vec<&str> = cells.iter().map(String::as_str).collect();
    let set = set_files(&cells, &["panda-1"], &["zenohd"]);
    let template = read(&deploy().join("k8s/secrets.template.yaml"));
    for name in server_set.iter().chain(&router_set).chain(&keys(o("Secret/dmp-client-tokens"), "stringData"))
    {
        assert!(set.contains(name), "{name} is not a file of a set");
        assert!(
            template.contains(&format!("$S/{name}")),
            "the template does not say where {name} comes from"
        );
    }
    for cell in &cells {
        assert!(
            template.contains(&format!("--cell {cell}")),
            "the template's access init lacks the cell {cell}"
        );
    }

    // The configuration file: the server's own Config reads it.
    let configmap = o("ConfigMap/dmp-server-config");
    let text = configmap["data"]["dmp-server.toml"].as_str().unwrap();
    let config: dmp_server::config::Config =
        toml::from_str(text).expect("the ConfigMap's dmp-server.toml loads");
    assert_eq!(config.grpc_addr.port(), grpc_port);
    assert_eq!(config.metrics_addr.map(|a| a.port()), Some(metrics_port));
    assert_eq!(config.data_dir.to_str(), Some(docker.volume.as_str()));
    let security = &config.security;
    for path in [&security.access, &security.tls_cert, &security.tls_key, &security.tls_client_ca] {
        let path = path.as_ref().expect("TLS and the access file are on").to_str().unwrap().to_owned();
        let name = path.strip_prefix(&format!("{SET_DIR}/")).expect("in the set's mount");
        assert!(server_set.contains(name), "{path} is not in the Secret dmp-server-set");
    }
    let router_port = router_listen_port(&cells);
    assert_eq!(config.zenoh.mode, "client");
    assert_eq!(config.zenoh.connect, [format!("tls/zenohd:{router_port}")]);
    // The lease: deploy/zenoh-lease.json5, a key of the same ConfigMap, mounted with dmp-server.toml.
    let lease = config.zenoh.config_file.as_ref().expect("zenoh.config_file: the lease");
    let key = lease.file_name().unwrap().to_str().unwrap();
    assert_eq!(
        configmap["data"][key].as_str(),
        Some(read(&deploy().join("zenoh-lease.json5")).as_str()),
        "the ConfigMap's {key} is deploy/zenoh-lease.json5"
    );

    // The StatefulSet: its arguments parse, a volume per pod for the store, the probes over TLS.
    let pod = &statefulset["spec"]["template"]["spec"];
    let c = &pod["containers"][0];
    let env: BTreeSet<&str> =
        c["env"].as_array().unwrap().iter().map(|e| e["name"].as_str().unwrap()).collect();
    let args: Vec<String> = strings(&c["args"], "dmp-server args")
        .into_iter()
        .map(|a| {
            if a.starts_with("$(") {
                assert!(env.contains(&a[2..a.len() - 1]), "{a} is not an env variable of the container");
            }
            a.replace("$(POD_NAME)", "dmp-server-0")
        })
        .collect();
    let parsed = dmp_server_args(&args, "StatefulSet");
    let cell = parsed.cell.expect("--cell");
    dmp_proto::keys::check_name("cell", &cell).expect("a pod's name is a valid cell");
    let config_dir = mount_of(pod, c, "configMap", "dmp-server-config");
    let config_path = parsed.config.expect("--config");
    assert_eq!(config_path, std::path::Path::new(&config_dir).join("dmp-server.toml"));
    assert_eq!(
        lease.parent(),
        Some(std::path::Path::new(&config_dir)),
        "the lease is in the ConfigMap's mount"
    );
    assert_eq!(mount_of(pod, c, "secret", "dmp-server-set"), SET_DIR);
    let ports = named_ports(c);
    assert_eq!(ports.values().copied().collect::<BTreeSet<_>>(), docker.exposed);
    assert_eq!((ports["grpc"], ports["metrics"]), (grpc_port, metrics_port));
    let annotations = &statefulset["spec"]["template"]["metadata"]["annotations"];
    assert_eq!(annotations["prometheus.io/port"].as_str(), Some(metrics_port.to_string().as_str()));
    let claim = &statefulset["spec"]["volumeClaimTemplates"][0]["metadata"]["name"];
    let data_mount =
        c["volumeMounts"].as_array().unwrap().iter().find(|m| m["name"] == *claim).expect("the store");
    assert_eq!(data_mount["mountPath"].as_str(), Some(docker.volume.as_str()));
    assert_eq!(pod["securityContext"]["runAsUser"], 65532, "the image's user");
    for probe in ["startupProbe", "livenessProbe", "readinessProbe"] {
        let command = strings(&c[probe]["exec"]["command"], probe);
        assert_eq!(command[0], "grpc_health_probe", "{probe}");
        assert!(docker.binaries.contains("grpc_health_probe"));
        let flag =
            |name: &str| command.iter().find_map(|a| a.strip_prefix(&format!("-{name}="))).map(str::to_owned);
        assert_eq!(flag("addr").map(|a| port_of(&a)), Some(grpc_port), "{probe}");
        assert!(command.contains(&"-tls".to_owned()), "{probe}: TLS is on");
        let ca = flag("tls-ca-cert").expect("-tls-ca-cert");
        assert_eq!(set_paths_in(&[ca], &set, probe).into_iter().collect::<Vec<_>>(), ["ca.pem"]);
        if let Some(service) = flag("service") {
            assert_eq!(service, dmp_proto::v1::scene_service_server::SERVICE_NAME, "{probe}");
        }
    }
    let service = o("Service/dmp-server");
    assert_eq!(statefulset["spec"]["serviceName"], "dmp-server");
    for p in service["spec"]["ports"].as_array().unwrap() {
        let target = p["targetPort"].as_str().unwrap();
        assert_eq!(p["port"].as_u64().map(|v| v as u16), Some(ports[target]), "Service port {target}");
    }

    // The router: the official image, the set's configuration, the storage, its Service.
    let zenohd = o("Deployment/zenohd");
    let pod = &zenohd["spec"]["template"]["spec"];
    let c = &pod["containers"][0];
    assert_eq!(c["image"].as_str(), Some(format!("eclipse/zenoh:{}", crate::zenoh_version()).as_str()));
    let args = strings(&c["args"], "zenohd args");
    check_router_args(&args, &set, "k8s zenohd");
    for name in set_paths_in(&args, &set, "zenohd") {
        assert!(router_set.contains(&name), "{name} is not in the Secret zenohd-set");
    }
    assert_eq!(mount_of(pod, c, "secret", "zenohd-set"), SET_DIR);
    assert_eq!(named_ports(c)["zenoh"], router_port);
    let service = o("Service/zenohd");
    assert_eq!(service["spec"]["ports"][0]["port"].as_u64(), Some(router_port.into()));
}
