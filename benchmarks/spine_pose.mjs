// Pose a Spine skeleton with Esoteric Software's spine-core runtime at every frame and print the
// "drawing" slot's world vertices as JSON, one array per frame. Used by benchmarks/spine_runtime.py.
// The runtime is not a dependency of toonmotion (its licence does not allow shipping it): install it
// yourself, under the Spine Runtimes License, with
//   npm install --no-save @esotericsoftware/spine-core@~4.2
// Usage: node benchmarks/spine_pose.mjs SKELETON.json ATLAS.atlas ANIMATION FPS FRAMES
import fs from "node:fs";
import * as spine from "@esotericsoftware/spine-core";
const [jsonPath, atlasPath, name, fps, frames] = process.argv.slice(2);
const atlas = new spine.TextureAtlas(fs.readFileSync(atlasPath, "utf8"));
const data = new spine.SkeletonJson(new spine.AtlasAttachmentLoader(atlas)).readSkeletonData(fs.readFileSync(jsonPath, "utf8"));
const skeleton = new spine.Skeleton(data);
const animation = data.findAnimation(name);
const out = [];
for (let t = 0; t < Number(frames); t++) {
  skeleton.setToSetupPose();
  animation.apply(skeleton, 0, t / Number(fps), false, null, 1, spine.MixBlend.setup, spine.MixDirection.mixIn);
  skeleton.updateWorldTransform(spine.Physics.none);
  const slot = skeleton.findSlot("drawing");
  const mesh = slot.getAttachment();
  const vertices = new Float32Array(mesh.worldVerticesLength);
  mesh.computeWorldVertices(slot, 0, mesh.worldVerticesLength, vertices, 0, 2);
  out.push(Array.from(vertices));
}
console.log(JSON.stringify(out));
