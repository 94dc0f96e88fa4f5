// Talks to an OPC UA server with a client nobody here wrote and that is not the library our
// server is built with: node-opcua under node, installed by scripts/install-opcua-client.sh
// into .tools/opcua-client/. Takes one JSON plan, runs its steps in one session and prints one
// JSON result on stdout (node-opcua's own log lines go to stderr).
//
//   node tests/support/opcua_client.cjs '{"endpoint": ..., "steps": [...]}'
//   node tests/support/opcua_client.cjs < plan.json
//
// Plan: {"endpoint": "opc.tcp://127.0.0.1:4840", "security": "SignAndEncrypt" | "Sign" |
// "None", "user": "name" | null, "password": "secret" | null, "pki": "DIR", "steps": [...]},
// where pki is the directory for the client's own certificates (created if need be, the
// server's certificate accepted on first sight) and a secured channel uses Basic256Sha256.
// Without a user the session is anonymous, and the anonymous token is sent even when the
// endpoint offers no anonymous token policy, so that it is the server that refuses it
// ("force_anonymous": false leaves node-opcua to refuse it itself, without asking).
// A step, and the entry of "results" it gives:
//   {"browse": NODE_ID, "depth": N (1)}  ->  {"browse": NODE}: the node and, to depth N, the
//       nodes it refers to by HierarchicalReferences (forward, subtypes included). A NODE is
//       {nodeId, browseName ("Name" in namespace 0, "2:Name" elsewhere), displayName, nodeClass
//       ("Object", "Variable", ...), referenceType and typeDefinition (not on the root),
//       children: [NODE...] (above depth N only), cycle: true (a node that is its own
//       ancestor, not followed)}, a Variable or VariableType also dataType (its name: "Int16",
//       ...), valueRank, arrayDimensions (list or null), description (text or null),
//       accessLevel, userAccessLevel (numbers), and attributeErrors {name: status} for any of
//       those that could not be read (given as null).
//   {"read": [NODE_ID, ...]}  ->  {"read": [{node, value, dataType, statusCode,
//       sourceTimestamp, serverTimestamp}, ...]}
//   {"write": [{"node": NODE_ID, "value": VALUE, "dataType": "Int16"}, ...]}  ->  {"write":
//       [{node, statusCode}, ...]}; without dataType the node's own built-in type is used; a
//       list is written as an array; when the Write service failed as a whole or the value
//       could not be made, the item also has error and message.
//   {"subscribe": {"nodes": [NODE_ID, ...], "sampling_ms": 100, "publishing_ms": 100,
//                  "for_ms": 2000}}  ->  {"subscribe": [{node, statusCode,
//       revisedSamplingInterval, notifications: [{value, dataType, statusCode,
//       sourceTimestamp, serverTimestamp, receivedAt (Date.now() as it arrived)}, ...]}, ...],
//       revisedPublishingInterval}: one subscription, one monitored item per node (queue 100,
//       timestamps Both), the notifications of for_ms.
//   {"endpoints": {}}  ->  {"endpoints": [{endpointUrl, securityMode, securityPolicyUri,
//       securityLevel, applicationUri, serverCertificate (base64 DER), userIdentityTokens:
//       [{policyId, tokenType, securityPolicyUri}]}, ...]} (GetEndpoints)
// A step that fails gives {"error", "message"} instead, and the next step still runs; error is
// the status code's name where there is one ("BadNodeIdUnknown"), else the message.
//
// The result: {"client": "node-opcua 2.186.4", "security", "results": [...], "timings":
// {load_ms, connect_ms, session_ms, steps_ms, total_ms}}, or, when the connection or the
// session failed, {"error", "message"} alone. Values are JSON: Int64 and UInt64 as decimal
// strings, arrays as lists, DateTime as ISO text, ByteString as base64, LocalizedText as its
// text, QualifiedName, NodeId and StatusCode as their text, NaN and infinities as "NaN",
// "Infinity", "-Infinity"; timestamps ISO text or null; status codes their names ("Good").
// Connecting and making the session get at most "timeout_ms" (10000) each, else the result is
// {"error": "Timeout", "message"}. A plan with no pki or an unknown security gives {"error":
// "InvalidPlan", "message"}. The exit status is 0 whenever a result was printed, 2 for a plan
// that is not JSON.
"use strict";

const started = Date.now();
const util = require("node:util");
// node-opcua logs with console.log; stdout is for the one JSON result.
const toStderr = (...args) => process.stderr.write(util.format(...args) + "\n");
console.log = toStderr;
console.info = toStderr;
console.warn = toStderr;
console.debug = toStderr;

const fs = require("node:fs");
const path = require("node:path");
const { createRequire } = require("node:module");

const tools = path.resolve(__dirname, "..", "..", ".tools", "opcua-client");
const requireTool = createRequire(path.join(tools, "package.json"));
// On node 20 (and only there) node-opcua, as it loads, generates a 4096-bit RSA key in the
// background to see whether RSA PKCS#1 v1.5 decryption works (CVE-2023-46809), only to print
// a warning. Basic256Sha256 does not use it, and the process cannot exit until the key is
// made: 1 to 3 s more per run. The check looks at process.version, so it is shown another
// one while node-opcua loads, and the real one again after.
const nodeVersion = Object.getOwnPropertyDescriptor(process, "version");
Object.defineProperty(process, "version", { ...nodeVersion, value: "v22.13.0" });
let opcua;
try {
  opcua = requireTool("node-opcua");
} finally {
  Object.defineProperty(process, "version", nodeVersion);
}
const version = JSON.parse(
  fs.readFileSync(path.join(tools, "node_modules", "node-opcua", "package.json"), "utf-8"),
).version;
const loaded = Date.now();

const {
  AttributeIds,
  BrowseDirection,
  ClientMonitoredItem,
  DataType,
  MessageSecurityMode,
  NodeClass,
  OPCUACertificateManager,
  OPCUAClient,
  SecurityPolicy,
  TimestampsToReturn,
  UserTokenPolicy,
  UserTokenType,
  VariantArrayType,
  resolveNodeId,
} = opcua;

// --- values to JSON and back ------------------------------------------------------------

function int64Text(pair, signed) {
  const bits = (BigInt(pair[0] >>> 0) << 32n) | BigInt(pair[1] >>> 0);
  return (signed ? BigInt.asIntN(64, bits) : bits).toString();
}

function scalarJson(type, value) {
  if (value === null || value === undefined) return null;
  switch (type) {
    case DataType.Int64:
      return Array.isArray(value) ? int64Text(value, true) : String(value);
    case DataType.UInt64:
      return Array.isArray(value) ? int64Text(value, false) : String(value);
    case DataType.Float:
    case DataType.Double:
      return Number.isFinite(value) ? value : String(value);
    case DataType.DateTime:
      return value instanceof Date && !Number.isNaN(value.getTime()) ? value.toISOString() : null;
    case DataType.ByteString:
      return Buffer.from(value).toString("base64");
    case DataType.LocalizedText:
      return value.text ?? null;
    case DataType.QualifiedName:
    case DataType.NodeId:
    case DataType.ExpandedNodeId:
      return value.toString();
    case DataType.StatusCode:
      return value.name;
    case DataType.Variant:
      return variantJson(value);
    case DataType.ExtensionObject:
    case DataType.DiagnosticInfo:
    case DataType.DataValue:
      return typeof value.toJSON === "function" ? value.toJSON() : String(value);
    default:
      return typeof value === "bigint" ? value.toString() : value;
  }
}

function variantJson(variant) {
  if (!variant) return null;
  const type = variant.dataType;
  if (variant.arrayType === VariantArrayType.Scalar) return scalarJson(type, variant.value);
  if (variant.value === null || variant.value === undefined) return null;
  // a Matrix is given flat, in the server's order (see the node's arrayDimensions)
  return Array.from(variant.value, (item) => scalarJson(type, item));
}

function typeName(variant) {
  return variant ? DataType[variant.dataType] : null;
}

function isoOrNull(date) {
  return date instanceof Date && !Number.isNaN(date.getTime()) ? date.toISOString() : null;
}

function fromJson(type, value) {
  switch (type) {
    case DataType.Int64:
    case DataType.UInt64:
      return String(value);
    case DataType.DateTime:
      return new Date(value);
    case DataType.ByteString:
      return value === null ? null : Buffer.from(value, "base64");
    case DataType.Float:
    case DataType.Double:
      return typeof value === "string" ? Number(value) : value;
    default:
      return value;
  }
}

function statusName(status) {
  return status ? status.name : null;
}

// "BadUserAccessDenied" out of whatever node-opcua threw
function errorName(error) {
  if (error && error.statusCode && error.statusCode.name) return error.statusCode.name;
  const header = error && error.response && error.response.responseHeader;
  const serviceResult = header && header.serviceResult;
  if (serviceResult && serviceResult.name && serviceResult.name !== "Good") {
    return serviceResult.name;
  }
  const message = messageOf(error);
  const found = message.match(/\b(Bad[A-Z][A-Za-z]+)\b/);
  return found ? found[1] : message;
}

function messageOf(error) {
  return String(error && error.message ? error.message : error);
}

function failure(error) {
  return { error: errorName(error), message: messageOf(error) };
}

// --- steps --------------------------------------------------------------------------------

const VARIABLE_ATTRIBUTES = [
  ["dataType", AttributeIds.DataType],
  ["valueRank", AttributeIds.ValueRank],
  ["arrayDimensions", AttributeIds.ArrayDimensions],
  ["description", AttributeIds.Description],
  ["accessLevel", AttributeIds.AccessLevel],
  ["userAccessLevel", AttributeIds.UserAccessLevel],
];

async function nameOf(session, names, nodeId) {
  const key = nodeId.toString();
  if (!names.has(key)) {
    const [browseName] = await session.read([{ nodeId, attributeId: AttributeIds.BrowseName }]);
    names.set(key, browseName.statusCode.isGood() ? browseName.value.value.name : key);
  }
  return names.get(key);
}

async function references(session, nodeId) {
  let result = await session.browse({
    nodeId,
    browseDirection: BrowseDirection.Forward,
    referenceTypeId: "HierarchicalReferences",
    includeSubtypes: true,
    nodeClassMask: 0,
    resultMask: 0x3f,
  });
  const found = [];
  for (;;) {
    if (!result.statusCode.isGood()) {
      throw Object.assign(new Error(`browse ${nodeId}: ${result.statusCode.name}`), {
        statusCode: result.statusCode,
      });
    }
    found.push(...(result.references || []));
    if (!result.continuationPoint || !result.continuationPoint.length) break;
    result = await session.browseNext(result.continuationPoint, false);
  }
  return found;
}

async function describe(session, names, nodeId, nodeClass, tree) {
  if (nodeClass !== NodeClass.Variable && nodeClass !== NodeClass.VariableType) return;
  const values = await session.read(
    VARIABLE_ATTRIBUTES.map(([, attributeId]) => ({ nodeId, attributeId })),
  );
  VARIABLE_ATTRIBUTES.forEach(([name], index) => {
    const dataValue = values[index];
    if (!dataValue.statusCode.isGood()) {
      tree[name] = null;
      (tree.attributeErrors ||= {})[name] = dataValue.statusCode.name;
      return;
    }
    const value = dataValue.value.value;
    if (name === "arrayDimensions") tree[name] = value === null ? null : Array.from(value);
    else if (name === "description") tree[name] = value ? value.text ?? null : null;
    else tree[name] = value;
  });
  if (tree.dataType) tree.dataType = await nameOf(session, names, tree.dataType);
}

async function browseStep(session, names, step) {
  const depth = step.depth ?? 1;
  const rootId = resolveNodeId(step.browse);
  const [browseName, displayName, nodeClass] = await session.read(
    [AttributeIds.BrowseName, AttributeIds.DisplayName, AttributeIds.NodeClass].map(
      (attributeId) => ({ nodeId: rootId, attributeId }),
    ),
  );
  if (!nodeClass.statusCode.isGood()) {
    return { error: nodeClass.statusCode.name, message: `read NodeClass of ${step.browse}` };
  }
  const root = {
    nodeId: rootId.toString(),
    browseName: browseName.value.value ? browseName.value.value.toString() : null,
    displayName: displayName.value.value ? displayName.value.value.text ?? null : null,
    nodeClass: NodeClass[nodeClass.value.value],
  };
  const visit = async (tree, nodeId, nodeClassValue, level, above) => {
    await describe(session, names, nodeId, nodeClassValue, tree);
    if (level >= depth) return;
    tree.children = [];
    for (const reference of await references(session, nodeId)) {
      const childId = reference.nodeId;
      const child = {
        nodeId: childId.toString(),
        browseName: reference.browseName.toString(),
        displayName: reference.displayName.text ?? null,
        nodeClass: NodeClass[reference.nodeClass],
        referenceType: await nameOf(session, names, reference.referenceTypeId),
        typeDefinition: reference.typeDefinition ? reference.typeDefinition.toString() : null,
      };
      tree.children.push(child);
      if (childId.serverIndex) continue; // on another server
      if (above.has(child.nodeId)) {
        child.cycle = true; // an ancestor of itself: not followed again
        continue;
      }
      const path = new Set(above).add(child.nodeId);
      await visit(child, childId, reference.nodeClass, level + 1, path);
    }
  };
  await visit(root, rootId, nodeClass.value.value, 0, new Set([root.nodeId]));
  return { browse: root };
}

async function readStep(session, step) {
  const values = await session.read(
    step.read.map((nodeId) => ({ nodeId: resolveNodeId(nodeId), attributeId: AttributeIds.Value })),
    0,
  );
  return {
    read: values.map((dataValue, index) => ({
      node: step.read[index],
      value: variantJson(dataValue.value),
      dataType: typeName(dataValue.value),
      statusCode: statusName(dataValue.statusCode),
      sourceTimestamp: isoOrNull(dataValue.sourceTimestamp),
      serverTimestamp: isoOrNull(dataValue.serverTimestamp),
    })),
  };
}

async function writeStep(session, step) {
  const written = [];
  for (const item of step.write) {
    try {
      const nodeId = resolveNodeId(item.node);
      let type;
      if (item.dataType) {
        type = DataType[item.dataType];
        if (typeof type !== "number") throw new Error(`unknown dataType ${item.dataType}`);
      } else {
        type = await session.getBuiltInDataType(nodeId);
      }
      const list = Array.isArray(item.value);
      const value = {
        dataType: type,
        arrayType: list ? VariantArrayType.Array : VariantArrayType.Scalar,
        value: list ? item.value.map((v) => fromJson(type, v)) : fromJson(type, item.value),
      };
      const status = await session.write({
        nodeId,
        attributeId: AttributeIds.Value,
        value: { value },
      });
      written.push({ node: item.node, statusCode: statusName(status) });
    } catch (error) {
      // the service itself failed (a ServiceFault), or the value could not be made
      const failed = failure(error);
      const statusCode = failed.error.startsWith("Bad") ? failed.error : null;
      written.push({ node: item.node, statusCode, ...failed });
    }
  }
  return { write: written };
}

async function subscribeStep(session, step) {
  const plan = step.subscribe;
  const subscription = await session.createSubscription2({
    requestedPublishingInterval: plan.publishing_ms ?? 100,
    requestedLifetimeCount: 100,
    requestedMaxKeepAliveCount: 10,
    maxNotificationsPerPublish: 0,
    publishingEnabled: true,
    priority: 1,
  });
  const items = [];
  try {
    for (const node of plan.nodes) {
      const entry = { node, statusCode: null, revisedSamplingInterval: null, notifications: [] };
      items.push(entry);
      try {
        const item = ClientMonitoredItem.create(
          subscription,
          { nodeId: resolveNodeId(node), attributeId: AttributeIds.Value },
          { samplingInterval: plan.sampling_ms ?? 100, discardOldest: true, queueSize: 100 },
          TimestampsToReturn.Both,
        );
        item.on("changed", (dataValue) => {
          entry.notifications.push({
            value: variantJson(dataValue.value),
            dataType: typeName(dataValue.value),
            statusCode: statusName(dataValue.statusCode),
            sourceTimestamp: isoOrNull(dataValue.sourceTimestamp),
            serverTimestamp: isoOrNull(dataValue.serverTimestamp),
            receivedAt: Date.now(),
          });
        });
        await new Promise((resolve) => {
          const timer = setTimeout(() => {
            Object.assign(entry, { error: "Timeout", message: "no reply to CreateMonitoredItems" });
            resolve();
          }, 10000);
          item.once("initialized", () => resolve(clearTimeout(timer)));
          item.once("err", (message) => {
            Object.assign(entry, failure(message));
            resolve(clearTimeout(timer));
          });
        });
        entry.statusCode = statusName(item.statusCode);
        if (item.result) entry.revisedSamplingInterval = item.result.revisedSamplingInterval;
      } catch (error) {
        Object.assign(entry, failure(error));
      }
    }
    await new Promise((resolve) => setTimeout(resolve, plan.for_ms ?? 2000));
  } finally {
    await subscription.terminate().catch(() => {});
  }
  return {
    subscribe: items,
    revisedPublishingInterval: subscription.publishingInterval,
  };
}

async function endpointsStep(client) {
  const endpoints = await client.getEndpoints();
  return {
    endpoints: endpoints.map((endpoint) => ({
      endpointUrl: endpoint.endpointUrl,
      securityMode: MessageSecurityMode[endpoint.securityMode],
      securityPolicyUri: endpoint.securityPolicyUri,
      securityLevel: endpoint.securityLevel,
      applicationUri: endpoint.server ? endpoint.server.applicationUri : null,
      serverCertificate: endpoint.serverCertificate
        ? endpoint.serverCertificate.toString("base64")
        : null,
      userIdentityTokens: (endpoint.userIdentityTokens || []).map((policy) => ({
        policyId: policy.policyId,
        tokenType: UserTokenType[policy.tokenType],
        securityPolicyUri: policy.securityPolicyUri || null,
      })),
    })),
  };
}

async function runStep(client, session, names, step) {
  try {
    if ("endpoints" in step) return await endpointsStep(client);
    if ("browse" in step) return await browseStep(session, names, step);
    if ("read" in step) return await readStep(session, step);
    if ("write" in step) return await writeStep(session, step);
    if ("subscribe" in step) return await subscribeStep(session, step);
    return { error: "UnknownStep", message: JSON.stringify(step) };
  } catch (error) {
    return failure(error);
  }
}

// --- the session ----------------------------------------------------------------------------

const MODES = {
  None: MessageSecurityMode.None,
  Sign: MessageSecurityMode.Sign,
  SignAndEncrypt: MessageSecurityMode.SignAndEncrypt,
};

// node-opcua will not send an anonymous token to an endpoint that offers none; to see the
// server refuse one itself, the endpoint descriptions it got (getEndpoints gives the ones it
// keeps and picks the session's endpoint from) are made to offer one.
function offerAnonymous(endpoint) {
  const tokens = endpoint.userIdentityTokens || [];
  if (tokens.some((policy) => policy.tokenType === UserTokenType.Anonymous)) return;
  endpoint.userIdentityTokens = [
    ...tokens,
    new UserTokenPolicy({ policyId: "Anonymous", tokenType: UserTokenType.Anonymous }),
  ];
}

// node-opcua waits for a server that accepted the connection but never answers (HEL/ACK)
// until the server hangs up: the connection and session get at most timeout_ms.
function within(ms, promise, what) {
  let timer;
  const late = new Promise((_, reject) => {
    timer = setTimeout(
      () => reject(Object.assign(new Error(`${what}: no answer in ${ms} ms`), { timeout: true })),
      ms,
    );
  });
  return Promise.race([promise, late]).finally(() => clearTimeout(timer));
}

const quietly = (promise) => within(2000, promise, "closing").catch(() => {});

async function run(plan) {
  const security = plan.security ?? "None";
  if (!(security in MODES)) return { error: "InvalidPlan", message: `no security ${security}` };
  if (!plan.pki) return { error: "InvalidPlan", message: "the plan names no pki directory" };
  const certificates = new OPCUACertificateManager({
    rootFolder: plan.pki,
    automaticallyAcceptUnknownCertificate: true,
  });
  let client = null;
  let session = null;
  const timings = { load_ms: loaded - started };
  const limit = plan.timeout_ms ?? 10000;
  try {
    await certificates.initialize();
    client = OPCUAClient.create({
      applicationName: "padt-test-client",
      clientCertificateManager: certificates,
      securityMode: MODES[security],
      securityPolicy: security === "None" ? SecurityPolicy.None : SecurityPolicy.Basic256Sha256,
      endpointMustExist: false,
      keepSessionAlive: false,
      requestedSessionTimeout: 60000,
      connectionStrategy: { maxRetry: 0, initialDelay: 100, maxDelay: 200 },
      transportTimeout: 5000,
    });
    let mark = Date.now();
    await within(limit, client.connect(plan.endpoint), "connect");
    timings.connect_ms = Date.now() - mark;
    if (plan.user == null && plan.force_anonymous !== false) {
      (await within(limit, client.getEndpoints(), "GetEndpoints")).forEach(offerAnonymous);
    }
    mark = Date.now();
    const identity =
      plan.user == null
        ? { type: UserTokenType.Anonymous }
        : { type: UserTokenType.UserName, userName: plan.user, password: plan.password ?? "" };
    session = await within(limit, client.createSession(identity), "CreateSession");
    timings.session_ms = Date.now() - mark;
  } catch (error) {
    if (client) await quietly(client.disconnect());
    await quietly(certificates.dispose());
    return error && error.timeout ? { error: "Timeout", message: error.message } : failure(error);
  }
  const names = new Map();
  const results = [];
  const mark = Date.now();
  for (const step of plan.steps || []) results.push(await runStep(client, session, names, step));
  timings.steps_ms = Date.now() - mark;
  await quietly(session.close());
  await quietly(client.disconnect());
  await quietly(certificates.dispose());
  timings.total_ms = Date.now() - started;
  return { client: `node-opcua ${version}`, security, results, timings };
}

function readPlan() {
  const text = process.argv[2] !== undefined ? process.argv[2] : fs.readFileSync(0, "utf-8");
  return JSON.parse(text);
}

async function main() {
  let plan;
  try {
    plan = readPlan();
  } catch (error) {
    process.stderr.write(`opcua_client.cjs: no plan: ${error.message}\n`);
    process.exit(2);
  }
  let result;
  try {
    result = await run(plan);
  } catch (error) {
    result = failure(error);
  }
  process.stdout.write(JSON.stringify(result) + "\n", () => process.exit(0));
}

main();
