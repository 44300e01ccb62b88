// cram-plans viewer: draws a belief state sent by the Lisp image (objects with their shapes and
// colours, articulated objects by forward kinematics from base pose and joint values), follows
// it live through server-sent events, and replays recorded runs step by step beside their task
// tree.  Uses three.js from Debian's libjs-three (global THREE).
var CramViewer = (function () {
  "use strict";
  THREE.Object3D.DefaultUp.set(0, 0, 1);

  function el(tag, cls, text) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }
  function poseMatrix(p) {
    return new THREE.Matrix4().compose(new THREE.Vector3(p[0], p[1], p[2]),
      new THREE.Quaternion(p[3], p[4], p[5], p[6]), new THREE.Vector3(1, 1, 1));
  }
  function base64Bytes(text) {
    var s = atob(text), a = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) a[i] = s.charCodeAt(i);
    return a;
  }
  function getJSON(url) {
    return fetch(url, { cache: "no-store" }).then(function (r) {
      if (!r.ok) return r.text().then(function (t) { throw new Error(url + ": " + t); });
      return r.json();
    });
  }

  // ---- meshes ---------------------------------------------------------------------------------
  var meshCache = {};
  function meshGeometry(meshes, id) {
    if (meshCache[id]) return meshCache[id];
    var m = meshes[id];
    if (!m) return Promise.reject(new Error("mesh " + id + " is not in the scene's mesh table"));
    var bytes = m.data ? Promise.resolve(base64Bytes(m.data).buffer)
      : fetch(m.url).then(function (r) { return r.arrayBuffer(); });
    meshCache[id] = bytes.then(function (buf) {
      if (m.format === "stl") return new THREE.STLLoader().parse(buf);
      var text = new TextDecoder().decode(buf);
      if (m.format === "obj") return new THREE.OBJLoader().parse(text);
      return new THREE.ColladaLoader().parse(text, "").scene;
    });
    return meshCache[id];
  }

  function material(color) {
    var c = color || [0.5, 0.5, 0.5, 1];
    return new THREE.MeshLambertMaterial({
      color: new THREE.Color(c[0], c[1], c[2]),
      transparent: c[3] < 1, opacity: c[3]
    });
  }

  // one visual (a geometry with origin and colour) as a three.js object; meshes arrive later
  function visualObject(v, meshes, pending) {
    var g = v.geometry, mat = material(v.color), holder = new THREE.Group(), geo = null;
    holder.applyMatrix(poseMatrix(v.origin));
    if (g.type === "box") geo = new THREE.BoxBufferGeometry(g.size[0], g.size[1], g.size[2]);
    else if (g.type === "sphere") geo = new THREE.SphereBufferGeometry(g.radius, 24, 16);
    else if (g.type === "cylinder") geo = new THREE.CylinderBufferGeometry(g.radius, g.radius, g.length, 24).rotateX(Math.PI / 2);
    else if (g.type === "cone") geo = new THREE.ConeBufferGeometry(g.radius, g.length, 24).rotateX(Math.PI / 2);
    else if (g.type === "hull") geo = new THREE.ConvexBufferGeometry(g.points.map(function (p) { return new THREE.Vector3(p[0], p[1], p[2]); }));
    else if (g.type === "plane") {
      var n = new THREE.Vector3(g.normal[0], g.normal[1], g.normal[2]).normalize();
      var floor = new THREE.Mesh(new THREE.PlaneBufferGeometry(30, 30), new THREE.MeshLambertMaterial({ color: 0xd8d8d0 }));
      floor.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
      floor.position.copy(n.clone().multiplyScalar(g.constant));
      floor.userData.floor = true;
      var grid = new THREE.GridHelper(30, 30, 0xaaaaaa, 0xc4c4bc);
      grid.rotation.x = Math.PI / 2; grid.position.z = 0.002;
      floor.add(grid);
      holder.add(floor);
      return holder;
    } else if (g.type === "mesh") {
      pending.push(meshGeometry(meshes, g.mesh).then(function (loaded) {
        var o = loaded.isBufferGeometry || loaded.isGeometry ? new THREE.Mesh(loaded, mat) : loaded.clone();
        if (!o.isMesh) o.traverse(function (c) { if (c.isMesh) c.material = mat; });
        o.scale.set(g.scale[0], g.scale[1], g.scale[2]);
        o.userData.mesh = g.mesh;
        holder.add(o);
      }));
      return holder;
    }
    if (geo) holder.add(new THREE.Mesh(geo, mat));
    return holder;
  }

  // ---- the world ---------------------------------------------------------------------------------
  function World(scene) {
    this.root = new THREE.Group();
    scene.add(this.root);
    this.objects = {};
  }
  World.prototype.build = function (data) {
    var self = this, pending = [];
    while (this.root.children.length) this.root.remove(this.root.children[0]);
    this.objects = {};
    (data.objects || []).forEach(function (d) {
      var entry = { desc: d, group: new THREE.Group(), links: [] };
      entry.group.name = d.name;
      if (d.kind === "articulated") {
        d.links.forEach(function (name, i) {
          var g = new THREE.Group();
          g.name = d.name + "/" + name; g.matrixAutoUpdate = false;
          entry.links.push(g); entry.group.add(g);
        });
        entry.childJoints = d.links.map(function () { return []; });
        d.joints.forEach(function (j, k) { if (j.parent >= 0) entry.childJoints[j.parent].push(k); });
        entry.linkWorld = d.links.map(function () { return new THREE.Matrix4(); });
      } else entry.group.matrixAutoUpdate = false;
      d.visuals.forEach(function (v) {
        var o = visualObject(v, data.meshes || {}, pending);
        (v.link >= 0 ? entry.links[v.link] : entry.group).add(o);
      });
      self.objects[d.name] = entry;
      self.root.add(entry.group);
    });
    return Promise.all(pending);
  };
  // forward kinematics: link world matrices from the base pose and the joint values
  World.prototype.setState = function (state) {
    var self = this;
    Object.keys(state).forEach(function (name) {
      var e = self.objects[name], s = state[name];
      if (!e) return;
      e.group.visible = true;
      if (e.desc.kind !== "articulated") {
        e.group.matrix.copy(poseMatrix(s.pose));
        e.group.matrixWorldNeedsUpdate = true;
        return;
      }
      var d = e.desc, stack = [d.root];
      e.linkWorld[d.root].copy(poseMatrix(s.pose));
      while (stack.length) {
        var l = stack.pop();
        e.childJoints[l].forEach(function (k) {
          var j = d.joints[k], q = s.joints[k] || 0, m = e.linkWorld[l].clone().multiply(poseMatrix(j.origin));
          var axis = new THREE.Vector3(j.axis[0], j.axis[1], j.axis[2]);
          if (j.type === "revolute" || j.type === "continuous")
            m.multiply(new THREE.Matrix4().makeRotationAxis(axis.normalize(), q));
          else if (j.type === "prismatic")
            m.multiply(new THREE.Matrix4().makeTranslation(axis.x * q, axis.y * q, axis.z * q));
          e.linkWorld[j.child].copy(m);
          stack.push(j.child);
        });
      }
      e.links.forEach(function (g, i) { g.matrix.copy(e.linkWorld[i]); g.matrixWorldNeedsUpdate = true; });
    });
    Object.keys(this.objects).forEach(function (n) { if (!state[n]) self.objects[n].group.visible = false; });
  };
  World.prototype.linkPosition = function (object, link) {
    var e = this.objects[object], i = e ? e.desc.links.indexOf(link) : -1;
    if (i < 0) return null;
    return new THREE.Vector3().setFromMatrixPosition(e.linkWorld[i]);
  };

  // ---- overlays -------------------------------------------------------------------------------
  function arrow(p, color, length) {
    var q = new THREE.Quaternion(p[3], p[4], p[5], p[6]);
    var dir = new THREE.Vector3(1, 0, 0).applyQuaternion(q);
    dir.z = 0; if (dir.lengthSq() < 1e-9) dir.set(1, 0, 0);
    return new THREE.ArrowHelper(dir.normalize(), new THREE.Vector3(p[0], p[1], 0.03), length, color, 0.08, 0.05);
  }
  function overlayObjects(list, world) {
    var g = new THREE.Group();
    (list || []).forEach(function (o) {
      if (o.type === "location") {
        if (o.heat) {
          var h = o.heat, w = h.width, ht = h.height, rgb = base64Bytes(h.rgb), px = new Uint8Array(w * ht * 4);
          for (var r = 0; r < ht; r++) for (var c = 0; c < w; c++) {
            var src = 3 * (r * w + c), dst = 4 * ((ht - 1 - r) * w + c);   // texture rows from -y
            px[dst] = rgb[src]; px[dst + 1] = rgb[src + 1]; px[dst + 2] = rgb[src + 2];
            px[dst + 3] = (rgb[src] === 40 && rgb[src + 1] === 40 && rgb[src + 2] === 40) ? 0 : 200;
          }
          var tex = new THREE.DataTexture(px, w, ht, THREE.RGBAFormat);
          tex.needsUpdate = true;
          var b = h.bounds, plane = new THREE.Mesh(new THREE.PlaneBufferGeometry(b[2] - b[0], b[3] - b[1]),
            new THREE.MeshBasicMaterial({ map: tex, transparent: true, depthWrite: false }));
          plane.position.set((b[0] + b[2]) / 2, (b[1] + b[3]) / 2, 0.01);
          plane.name = "heat-map";
          g.add(plane);
        }
        (o.samples || []).forEach(function (p) { g.add(arrow(p, 0x3060ff, 0.25)); });
        if (o.chosen) { var a = arrow(o.chosen, 0x10c010, 0.45); a.name = "chosen"; g.add(a); }
      } else if (o.type === "sweep") {
        // the moving link's path: grey up to the first contact, red from there on (the
        // sweeping segment), and the first contact as a red ball
        var pts = (o.path || []).map(function (p) { return new THREE.Vector3(p[0], p[1], p[2]); });
        var cut = Math.max(1, Math.min(pts.length - 1, Math.round(o.fraction * (pts.length - 1))));
        var before = pts.slice(0, cut + 1), after = pts.slice(cut);
        [[before, 0x777777], [after, 0xe01010]].forEach(function (part) {
          if (part[0].length < 2) return;
          var line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(part[0]),
                                    new THREE.LineBasicMaterial({ color: part[1] }));
          line.name = part[1] === 0xe01010 ? "sweep-path" : "sweep-approach"; g.add(line);
        });
        var hit = new THREE.Mesh(new THREE.SphereBufferGeometry(0.025, 16, 12), new THREE.MeshBasicMaterial({ color: 0xe01010 }));
        hit.position.set(o.point[0], o.point[1], o.point[2]); hit.name = "sweep-contact";
        g.add(hit);
      } else if (o.type === "target") {
        var t = new THREE.Mesh(new THREE.SphereBufferGeometry(0.04, 16, 12), new THREE.MeshBasicMaterial({ color: 0xff2020 }));
        t.position.set(o.point[0], o.point[1], o.point[2]); t.name = "target";
        g.add(t);
      }
    });
    return g;
  }
  // camera field of view of the robot: a frustum at its camera link (optical frame: z forward)
  function frustum(world, range) {
    var g = new THREE.Group();
    Object.keys(world.objects).forEach(function (n) {
      var e = world.objects[n], cam = e.desc.camera;
      if (!cam || !e.group.visible) return;
      var i = e.desc.links.indexOf(cam.link);
      if (i < 0) return;
      var hy = Math.tan(cam.fov * Math.PI / 360) * range, hx = hy * cam.aspect, pts = [];
      var corners = [[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]];
      corners.forEach(function (c, k) {
        var n2 = corners[(k + 1) % 4];
        pts.push(0, 0, 0, c[0], c[1], range, c[0], c[1], range, n2[0], n2[1], range);
      });
      var geo = new THREE.BufferGeometry();
      geo.addAttribute("position", new THREE.Float32BufferAttribute(pts, 3));
      var lines = new THREE.LineSegments(geo, new THREE.LineBasicMaterial({ color: 0xffa000 }));
      lines.matrixAutoUpdate = false; lines.matrix.copy(e.linkWorld[i]); lines.name = "fov";
      g.add(lines);
    });
    return g;
  }

  // ---- the application -------------------------------------------------------------------------
  function App(options) {
    var self = this;
    this.options = options;
    var app = document.getElementById("app");
    this.view = el("div", "view"); this.side = el("div", "side"); this.bar = el("div", "bar");
    app.appendChild(this.view); app.appendChild(this.side); app.appendChild(this.bar);
    this.status = el("div", "status", "connecting");
    this.view.appendChild(this.status);
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setClearColor(0xeef1f4);
    this.view.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x666660, 0.85));
    var sun = new THREE.DirectionalLight(0xffffff, 0.55); sun.position.set(3, -4, 8); this.scene.add(sun);
    this.camera = new THREE.PerspectiveCamera(50, 1, 0.05, 100);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(-4.5, -3, 4.2);
    this.controls = new THREE.OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(-0.5, 0.5, 0.6);
    this.world = new World(this.scene);
    this.overlay = new THREE.Group(); this.scene.add(this.overlay);
    this.fov = new THREE.Group(); this.scene.add(this.fov);
    this.showFov = true;
    this.report = document.createElement("pre");
    this.report.id = "cram-report"; this.report.style.display = "none";
    document.body.appendChild(this.report);
    window.addEventListener("resize", function () { self.resize(); });
    this.resize();
    var loop = function () { self.controls.update(); self.renderer.render(self.scene, self.camera); requestAnimationFrame(loop); };
    requestAnimationFrame(loop);
  }
  App.prototype.resize = function () {
    var w = this.view.clientWidth || 800, h = this.view.clientHeight || 600;
    this.renderer.setSize(w, h); this.camera.aspect = w / h; this.camera.updateProjectionMatrix();
  };
  App.prototype.setOverlays = function (list) {
    this.scene.remove(this.overlay);
    this.overlay = overlayObjects(list, this.world);
    this.scene.add(this.overlay);
  };
  App.prototype.setState = function (state) {
    this.world.setState(state);
    this.scene.remove(this.fov);
    this.fov = this.showFov ? frustum(this.world, 2.5) : new THREE.Group();
    this.scene.add(this.fov);
  };
  App.prototype.render = function () { this.controls.update(); this.renderer.render(this.scene, this.camera); };

  // what the page shows, for tests and tools: objects, their bounding boxes, link positions
  App.prototype.describe = function (extra) {
    var self = this, out = { mode: this.options.mode, objects: {} };
    this.scene.updateMatrixWorld(true);
    Object.keys(this.world.objects).forEach(function (n) {
      var e = self.world.objects[n], meshes = 0, box = new THREE.Box3();
      e.group.traverse(function (o) { if (o.isMesh && !o.userData.floor) { meshes++; box.expandByObject(o); } });
      var info = { kind: e.desc.kind, visible: e.group.visible, meshes: meshes,
                   box: box.isEmpty() ? null : [box.min.toArray(), box.max.toArray()] };
      if (e.desc.kind === "articulated") {
        info.links = {};
        e.desc.links.forEach(function (l, i) { info.links[l] = new THREE.Vector3().setFromMatrixPosition(e.linkWorld[i]).toArray(); });
      }
      out.objects[n] = info;
    });
    out.overlays = this.overlay.children.map(function (c) { return c.name || c.type; });
    out.pixels = this.pixelCounts();
    for (var k in extra || {}) out[k] = extra[k];
    return out;
  };
  // share of the picture that is not background, and of strongly red pixels (the bottle)
  App.prototype.pixelCounts = function () {
    this.render();
    var gl = this.renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    var px = new Uint8Array(w * h * 4), drawn = 0, red = 0;
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    for (var i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - 0xee) + Math.abs(px[i + 1] - 0xf1) + Math.abs(px[i + 2] - 0xf4) > 12) drawn++;
      if (px[i] > 120 && px[i + 1] < 70 && px[i + 2] < 70) red++;
    }
    return { width: w, height: h, drawn: drawn / (w * h), red: red };
  };
  App.prototype.publish = function (extra) {
    var d = this.describe(extra);
    this.report.textContent = JSON.stringify(d);
    document.title = document.title.replace(/ \[ready\]$/, "") + " [ready]";
    if (/[?&]report=1/.test(location.search)) {
      if (/[?&]image=1/.test(location.search)) d.image = this.renderer.domElement.toDataURL("image/png");
      fetch("report", { method: "POST", body: JSON.stringify(d) });
    }
    return d;
  };

  // ---- live mode ---------------------------------------------------------------------------------
  App.prototype.live = function () {
    var self = this, built = Promise.resolve(), runs = el("div", "runs");
    var fov = el("label", "toggle"), box = el("input"); box.type = "checkbox"; box.checked = true;
    box.onchange = function () { self.showFov = box.checked; };
    fov.appendChild(box); fov.appendChild(document.createTextNode(" camera field of view"));
    this.side.appendChild(el("h2", null, "Recorded runs")); this.side.appendChild(runs); this.side.appendChild(fov);
    this.bar.appendChild(el("span", "hint", "live: the belief state as it changes; open a recorded run to replay it"));
    var onScene = function (data) {
      built = self.world.build(data).then(function () {
        self.setState(data.state); self.setOverlays(data.overlays);
        self.status.textContent = "live: " + Object.keys(data.state).length + " objects";
        self.publish({ runs: self.runs || [] });
      }).catch(function (e) { self.status.textContent = "error: " + e.message; });
    };
    var src = new EventSource("events");
    src.addEventListener("scene", function (m) { onScene(JSON.parse(m.data)); });
    src.addEventListener("state", function (m) { var s = JSON.parse(m.data); built.then(function () { self.setState(s); }); });
    src.addEventListener("overlays", function (m) { var o = JSON.parse(m.data); built.then(function () { self.setOverlays(o); }); });
    src.addEventListener("runs", function (m) {
      self.runs = JSON.parse(m.data);
      runs.innerHTML = "";
      self.runs.slice().reverse().forEach(function (r) {
        var a = el("a", r.failed ? "run failed" : "run", r.label + " — " + r.steps + " steps" + (r.failed ? ", " + r.failed + " failed" : ""));
        a.href = "replay?run=" + r.id; runs.appendChild(a);
      });
    });
    src.onerror = function () { self.status.textContent = "disconnected (retrying)"; };
  };

  // ---- replay mode --------------------------------------------------------------------------------
  App.prototype.replay = function (run) {
    var self = this, steps = run.steps, nodes = {}, current = -1, timer = null;
    document.title = "cram-plans replay: " + run.label;
    var tree = el("div", "tree");
    this.side.appendChild(el("h2", null, run.label)); this.side.appendChild(tree);
    var nodeEl = function (n) {
      var li = el("li", "node " + n.outcome), row = el("div", "row");
      row.appendChild(el("span", "kind", n.kind)); row.appendChild(el("span", "name", n.name));
      row.appendChild(el("span", "dur", (n.duration * 1000).toFixed(1) + " ms"));
      if (n.failure) row.title = n.failure;
      if (n.first_step !== null && n.first_step !== undefined) {
        row.classList.add("link");
        row.onclick = function (ev) { ev.stopPropagation(); self.go(n.first_step); };
      }
      li.appendChild(row); nodes[n.id] = row;
      if (n.children && n.children.length) {
        var ul = el("ul"); n.children.forEach(function (c) { ul.appendChild(nodeEl(c)); }); li.appendChild(ul);
      }
      return li;
    };
    if (run.tree) { var ul = el("ul", "root"); ul.appendChild(nodeEl(run.tree)); tree.appendChild(ul); }
    var prev = el("button", null, "◀"), play = el("button", null, "play"), next = el("button", null, "▶");
    var slider = el("input"), label = el("span", "label"), ticks = el("div", "ticks");
    slider.type = "range"; slider.min = 0; slider.max = Math.max(0, steps.length - 1); slider.value = 0;
    [prev, play, next, slider, label].forEach(function (x) { self.bar.appendChild(x); });
    this.bar.appendChild(ticks);
    function sweepsOf(s) { return (s.overlays || []).filter(function (o) { return o.type === "sweep"; }); }
    steps.forEach(function (s, i) {
      var at = function (k) { return (steps.length > 1 ? 100 * k / (steps.length - 1) : 0); };
      if (i > 0 && sweepsOf(s).length) {   // the motion into this step swept through something
        var seg = el("span", "seg swept"); seg.style.left = at(i - 1) + "%"; seg.style.width = (at(i) - at(i - 1)) + "%";
        seg.title = i + ": " + sweepsOf(s).map(function (o) { return o.text; }).join("; ");
        seg.onclick = function () { self.go(i); }; ticks.appendChild(seg);
      }
      var t = el("span", s.failed ? "tick failed" : "tick"); t.title = i + ": " + s.label;
      t.style.left = at(i) + "%";
      t.onclick = function () { self.go(i); }; ticks.appendChild(t);
    });
    prev.onclick = function () { self.go(current - 1); };
    next.onclick = function () { self.go(current + 1); };
    slider.oninput = function () { self.go(parseInt(slider.value, 10)); };
    play.onclick = function () {
      if (timer) { clearInterval(timer); timer = null; play.textContent = "play"; return; }
      if (current >= steps.length - 1) self.go(0);
      play.textContent = "pause";
      timer = setInterval(function () {
        if (current >= steps.length - 1) { clearInterval(timer); timer = null; play.textContent = "play"; }
        else self.go(current + 1);
      }, 600);
    };
    this.go = function (i) {
      if (!steps.length) return;
      i = Math.max(0, Math.min(steps.length - 1, i));
      current = i; slider.value = i;
      var s = steps[i];
      self.setState(s.state);
      var latest = {};            // each kind of overlay: the latest up to this step
      for (var k = 0; k <= i; k++) (steps[k].overlays || []).forEach(function (o) { if (o.type !== "sweep") latest[o.type] = o; });
      self.setOverlays(Object.keys(latest).map(function (t) { return latest[t]; }).concat(sweepsOf(s)));
      label.textContent = "step " + (i + 1) + "/" + steps.length + ": " + s.label + (s.failed ? " (failed)" : "") +
        "  +" + s.offset.toFixed(3) + " s" +
        (function (sw) {   // the first contact of the motion's path, and how many more
          return sw.length ? " — sweeps " + sw[0].text + (sw.length > 1 ? " (and " + (sw.length - 1) + " more)" : "") : "";
        })(sweepsOf(s).slice().sort(function (a, b) { return a.fraction - b.fraction; }));
      label.className = s.failed ? "label failed" : "label";
      Object.keys(nodes).forEach(function (id) { nodes[id].classList.remove("current"); });
      if (s.node && nodes[s.node]) { nodes[s.node].classList.add("current"); nodes[s.node].scrollIntoView({ block: "nearest" }); }
      self.publish({ step: i, steps: steps.length, labels: steps.map(function (x) { return x.label; }),
                     failed: steps.map(function (x) { return x.failed; }) });
    };
    this.status.textContent = steps.length + " steps";
    return this.world.build(run).then(function () {
      var m = /[?&]step=(\d+)/.exec(location.search);
      self.go(m ? parseInt(m[1], 10) : steps.length - 1);
    });
  };

  function start(options) {
    var app = new App(options);
    window.cramViewer = app;
    if (options.mode === "live") app.live();
    else {
      var data = options.inline ? Promise.resolve(JSON.parse(document.getElementById("replay-data").textContent))
        : getJSON("run.json?run=" + options.run);
      data.then(function (run) { return app.replay(run); })
        .catch(function (e) { app.status.textContent = "error: " + e.message; });
    }
    return app;
  }
  return { start: start };
})();
