// The browser side of the Foxglove WebSocket protocol v1 (subprotocol foxglove.websocket.v1), as
// telegrasp-view speaks it: JSON control messages, binary Message Data frames carrying JSON.
// Subscribes to every advertised channel whose topic is in `topics`, reconnects when closed.

const SUBPROTOCOL = "foxglove.websocket.v1";
const MESSAGE_DATA = 0x01;

export class FoxgloveConnection {
  // onMessage(topic, message, stampNs: bigint), onState(text, connected)
  constructor(url, topics, { onMessage, onState }) {
    this.url = url;
    this.topics = new Set(topics);
    this.onMessage = onMessage;
    this.onState = onState;
    this.decoder = new TextDecoder();
    this.closed = false;
    this.connect();
  }

  connect() {
    this.topicBySubscription = new Map();
    this.ws = new WebSocket(this.url, [SUBPROTOCOL]);
    this.ws.binaryType = "arraybuffer";
    this.ws.onopen = () => this.onState(`connected to ${this.url}`, true);
    this.ws.onclose = () => {
      this.onState(`disconnected from ${this.url}; retrying`, false);
      if (!this.closed) setTimeout(() => this.connect(), 1000);
    };
    this.ws.onmessage = (event) => {
      if (typeof event.data === "string") this.control(JSON.parse(event.data));
      else this.data(new DataView(event.data));
    };
  }

  control(message) {
    if (message.op === "advertise") {
      const subscriptions = [];
      for (const channel of message.channels) {
        if (!this.topics.has(channel.topic) || channel.encoding !== "json") continue;
        // One subscription per channel: its id is the channel's.
        this.topicBySubscription.set(channel.id, channel.topic);
        subscriptions.push({ id: channel.id, channelId: channel.id });
      }
      if (subscriptions.length > 0) this.ws.send(JSON.stringify({ op: "subscribe", subscriptions }));
    } else if (message.op === "status" && message.level > 0) {
      console.warn(`telegrasp-view says: ${message.message}`);
    }
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
