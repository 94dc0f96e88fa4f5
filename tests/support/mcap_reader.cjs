// Reads an MCAP file with a reader nobody here wrote (the TypeScript @mcap/core, installed by
// scripts/install-mcap-reader.sh into .tools/mcap-reader/) and prints what it found as JSON:
// the header, schemas, channels, metadata, attachments and, per channel, the messages (count,
// first and last log time and sequence, the first and last decoded; with --all every one).
//
//   node tests/support/mcap_reader.cjs FILE.mcap [--all]
//
// The file is fed to McapStreamReader in pieces, as a stream consumer would: a file cut short
// (the writer was killed) is read up to its last whole record; "complete" says whether the
// footer was reached, "error" what stopped the reader, if anything did. Chunk CRCs are checked.
// Log times are nanoseconds and do not fit a JSON number: they are printed as strings.
"use strict";

const fs = require("node:fs");
const path = require("node:path");
const { createRequire } = require("node:module");

const tools = path.resolve(__dirname, "..", "..", ".tools", "mcap-reader");
const requireTool = createRequire(path.join(tools, "package.json"));
const { McapStreamReader } = requireTool("@mcap/core");
const fzstd = requireTool("fzstd");
const lz4 = requireTool("lz4js");
const version = JSON.parse(
  fs.readFileSync(path.join(tools, "node_modules", "@mcap", "core", "package.json"), "utf-8"),
).version;

const PIECE = 1 << 20;

function decompressHandlers() {
  return {
    zstd: (buffer, size) => fzstd.decompress(buffer, new Uint8Array(Number(size))),
    lz4: (buffer, size) => Uint8Array.from(lz4.decompress(buffer, Number(size))),
  };
}

function decoded(bytes) {
  const text = new TextDecoder("utf-8", { fatal: true }).decode(bytes);
  try {
    return JSON.parse(text);
  } catch (error) {
    return { not_json: String(error), text: text.slice(0, 200) };
  }
}

function read(file, all) {
  const reader = new McapStreamReader({ decompressHandlers: decompressHandlers() });
  const found = {
    reader: `@mcap/core ${version}`,
    file: path.basename(file),
    bytes: 0,
    header: null,
    complete: false,
    error: null,
    bytes_left: 0,
    schemas: [],
    channels: [],
    metadata: [],
    attachments: [],
    statistics: null,
    messages: {},
  };
  const schemas = new Map();
  const channels = new Map();
  const take = (record) => {
    switch (record.type) {
      case "Header":
        found.header = { profile: record.profile, library: record.library };
        break;
      case "Schema":
        if (!schemas.has(record.id)) {
          schemas.set(record.id, record);
          found.schemas.push({
            id: record.id,
            name: record.name,
            encoding: record.encoding,
            data: decoded(record.data),
          });
        }
        break;
      case "Channel":
        if (!channels.has(record.id)) {
          channels.set(record.id, record);
          const schema = schemas.get(record.schemaId);
          found.channels.push({
            id: record.id,
            topic: record.topic,
            message_encoding: record.messageEncoding,
            schema: schema ? schema.name : null,
            schema_id: record.schemaId,
          });
        }
        break;
      case "Message": {
        const topic = channels.get(record.channelId).topic;
        const time = record.logTime.toString();
        const data = decoded(record.data);
        let seen = found.messages[topic];
        if (!seen) {
          seen = found.messages[topic] = {
            count: 0,
            first_log_time: time,
            first_sequence: record.sequence,
            first: data,
          };
          if (all) seen.all = [];
        }
        seen.count += 1;
        seen.last_log_time = time;
        seen.last_sequence = record.sequence;
        seen.last = data;
        if (all) seen.all.push({ sequence: record.sequence, log_time: time, data });
        break;
      }
      case "Metadata":
        found.metadata.push({ name: record.name, metadata: Object.fromEntries(record.metadata) });
        break;
      case "Attachment": {
        const text = new TextDecoder("utf-8").decode(record.data);
        found.attachments.push({
          name: record.name,
          media_type: record.mediaType,
          log_time: record.logTime.toString(),
          bytes: record.data.byteLength,
          text,
        });
        break;
      }
      case "Statistics":
        found.statistics = {
          message_count: record.messageCount.toString(),
          schema_count: record.schemaCount,
          channel_count: record.channelCount,
          attachment_count: record.attachmentCount,
          metadata_count: record.metadataCount,
          chunk_count: record.chunkCount,
          channel_message_counts: Object.fromEntries(
            [...record.channelMessageCounts].map(([id, n]) => [String(id), n.toString()]),
          ),
        };
        break;
      default:
        break; // chunk and summary indexes, data end, footer
    }
  };
  const descriptor = fs.openSync(file, "r");
  const piece = Buffer.alloc(PIECE);
  try {
    for (;;) {
      const got = fs.readSync(descriptor, piece, 0, PIECE, null);
      if (got === 0) break;
      found.bytes += got;
      reader.append(new Uint8Array(piece.subarray(0, got)));
      for (let record; (record = reader.nextRecord()); ) take(record);
    }
  } catch (error) {
    found.error = String(error && error.message ? error.message : error);
  } finally {
    fs.closeSync(descriptor);
  }
  found.complete = found.error === null && reader.done();
  found.bytes_left = found.error === null ? reader.bytesRemaining() : null;
  return found;
}

function main() {
  const args = process.argv.slice(2);
  const all = args.includes("--all");
  const files = args.filter((a) => a !== "--all");
  if (files.length !== 1) {
    process.stderr.write("usage: node mcap_reader.cjs FILE.mcap [--all]\n");
    process.exit(2);
  }
  process.stdout.write(JSON.stringify(read(files[0], all)) + "\n");
}

main();
