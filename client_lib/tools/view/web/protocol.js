// The browser side of the Foxglove WebSocket protocol v1 (subprotocol foxglove.websocket.v1), as
// telegrasp-view speaks it: JSON control messages, binary Message Data frames carrying JSON.
// Subscribes to every advertised channel whose topic is in `topics`, reconnects when closed.
// With `publish` ({topic, schemaName}), advertises that client channel when the server offers
// clientPublish and sends messages on it (send()).

const SUBPROTOCOL = "foxglove.websocket.v1";
const MESSAGE_DATA = 0x01;
const PUBLISH_CHANNEL = 1;  // the id of the one client channel this side advertises

export class FoxgloveConnection {
  // url: a string, or a function giving it at each (re)connection. onMessage(topic, message,
  // stampNs: bigint), onState(text, connected), onServerInfo(serverInfo), onStatus(status).
  constructor(url, topics, { onMessage, onState, onServerInfo = () => {}, onStatus = () => {}, publish = null }) {
    this.url = url;
    this.topics = new Set(topics);
    this.onMessage = onMessage;
    this.onState = onState;
    this.onServerInfo = onServerInfo;
    this.onStatus = onStatus;
    this.publishing = publish;
    this.decoder = new TextDecoder();
    this.encoder = new TextEncoder();
    this.closed = false;
    this.connect();
  }

  connect() {
    this.topicBySubscription = new Map();
    this.canPublish = false;
    const url = typeof this.url === "function" ? this.url() : this.url;
    this.ws = new WebSocket(url, [SUBPROTOCOL]);
    this.ws.binaryType = "arraybuffer";
    this.ws.onopen = () => this.onState(`connected to ${url}`, true);
    this.ws.onclose = () => {
      this.canPublish = false;
      this.onState(`disconnected from ${url}; retrying`, false);
      if (!this.closed) setTimeout(() => this.connect(), 1000);
    };
    this.ws.onmessage = (event) => {
      if (typeof event.data === "string") this.control(JSON.parse(event.data));
      else this.data(new DataView(event.data));
    };
  }

  control(message) {
    if (message.op === "serverInfo") {
      if (this.publishing && (message.capabilities ?? []).includes("clientPublish")) {
        this.ws.send(JSON.stringify({ op: "advertise", channels: [{ id: PUBLISH_CHANNEL, topic: this.publishing.topic,
          encoding: "json", schemaName: this.publishing.schemaName }] }));
        this.canPublish = true;
      }
      this.onServerInfo(message);
    } else if (message.op === "advertise") {
      const subscriptions = [];
      for (const channel of message.channels) {
        if (!this.topics.has(channel.topic) || channel.encoding !== "json") continue;
        // One subscription per channel: its id is the channel's.
        this.topicBySubscription.set(channel.id, channel.topic);
        subscriptions.push({ id: channel.id, channelId: channel.id });
      }
      if (subscriptions.length > 0) this.ws.send(JSON.stringify({ op: "subscribe", subscriptions }));
    } else if (message.op === "status") {
      if (message.level > 0) console.warn(`telegrasp-view says: ${message.message}`);
      this.onStatus(message);
    }
  }

  // Sends `message` (JSON) on the published channel; false if it cannot now.
  send(message) {
    if (!this.canPublish || this.ws.readyState !== WebSocket.OPEN) return false;
    const payload = this.encoder.encode(JSON.stringify(message));
    const frame = new Uint8Array(5 + payload.length);
    frame[0] = MESSAGE_DATA;
    new DataView(frame.buffer).setUint32(1, PUBLISH_CHANNEL, true);
    frame.set(payload, 5);
    this.ws.send(frame);
    return true;
  }

  data(view) {
    if (view.byteLength < 13 || view.getUint8(0) !== MESSAGE_DATA) return;
    const topic = this.topicBySubscription.get(view.getUint32(1, true));
    if (topic === undefined) return;
    const stamp = view.getBigUint64(5, true);
    const payload = new Uint8Array(view.buffer, view.byteOffset + 13, view.byteLength - 13);
    this.onMessage(topic, JSON.parse(this.decoder.decode(payload)), stamp);
  }

  close() {
    this.closed = true;
    this.ws.close();
  }
}
