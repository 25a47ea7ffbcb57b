// Mount Foxglove Studio's App (from @foxglove/studio-base's bundle, whose exports are globals)
// with an in-memory app configuration and layout storage, and the file / remote-file data sources.
/* global React, ReactDOM */
"use strict";

class MemoryAppConfiguration {
  constructor(defaults) {
    this.values = new Map(Object.entries(defaults));
    this.listeners = new Map();
  }
  get(key) {
    return this.values.get(key);
  }
  async set(key, value) {
    this.values.set(key, value);
    for (const cb of this.listeners.get(key) ?? []) {
      cb(value);
    }
  }
  addChangeListener(key, cb) {
    if (!this.listeners.has(key)) {
      this.listeners.set(key, new Set());
    }
    this.listeners.get(key).add(cb);
  }
  removeChangeListener(key, cb) {
    this.listeners.get(key)?.delete(cb);
  }
}

class MemoryLayoutStorage {
  constructor() {
    this.byNamespace = new Map();
  }
  ns(namespace) {
    if (!this.byNamespace.has(namespace)) {
      this.byNamespace.set(namespace, new Map());
    }
    return this.byNamespace.get(namespace);
  }
  async list(namespace) {
    return Array.from(this.ns(namespace).values());
  }
  async get(namespace, id) {
    return this.ns(namespace).get(id);
  }
  async put(namespace, layout) {
    this.ns(namespace).set(layout.id, layout);
    return layout;
  }
  async delete(namespace, id) {
    this.ns(namespace).delete(id);
  }
  async importLayouts({ fromNamespace, toNamespace }) {
    for (const layout of this.ns(fromNamespace).values()) {
      this.ns(toNamespace).set(layout.id, layout);
    }
  }
}

const S = window.AppSetting;
const appConfiguration = new MemoryAppConfiguration({
  [S.COLOR_SCHEME]: "light",
  [S.TIMEZONE]: "UTC",
  [S.LAUNCH_PREFERENCE]: "web",
  [S.TELEMETRY_ENABLED]: false,
  [S.CRASH_REPORTING_ENABLED]: false,
  [S.HIDE_SIGN_IN_PROMPT]: true,
  [S.SHOW_OPEN_DIALOG_ON_STARTUP]: true,
  [S.UPDATES_ENABLED]: false,
});

const dataSources = [
  new window.McapLocalDataSourceFactory(),
  new window.Ros2LocalBagDataSourceFactory(),
  new window.RemoteDataSourceFactory(),
  new window.FoxgloveWebSocketDataSourceFactory(),
];

async function main() {
  await window.initI18n();
  ReactDOM.render(
  React.createElement(window.App, {
    deepLinks: [window.location.href],
    appConfiguration,
    dataSources,
    layoutStorage: new MemoryLayoutStorage(),
    extensionLoaders: [],
    enableGlobalCss: true,
    enableLaunchPreferenceScreen: false,
  }),
  document.getElementById("root"),
  );
}

void main();
