// The tour's touch_wall as a Unity scene (TouchWall.unity beside it: a camera, a light, the tool
// as a small sphere with HapticToolFollower, a flat box for the wall's surface, and this on a
// GameObject of its own): HapticToolFollower on a small sphere (the tool), this pointing
// `follower` at it. Once the follower's session is open, this
// registers the wall z < 0 (K = 1000 N/m, B = 1 N·s/m) and places a flat cube on it, so that what
// the hand feels is what the eye sees. On a simulated device nothing moves the tool unless the
// server's operator does (hapticctl, or the C++/Python touch_wall on the same server).
using Hapticd;
using Hapticd.Unity;
using UnityEngine;

public class TouchWallScene : MonoBehaviour
{
    public HapticToolFollower follower;
    [Tooltip("A thin box drawn where the wall's surface is (optional)")]
    public Transform wallSurface;

    private ObjectHandle wall_;

    private void Update()
    {
        if (wall_ != null || follower == null || follower.Client == null) return;
        var spec = WallSpec.Default;  // through the origin, normal +z (W)
        spec.Impedance = new Impedance(1000.0, 1.0);
        try
        {
            wall_ = follower.Client.AddWall(spec);
        }
        catch (HapticException e)
        {
            Debug.LogError("hapticd: " + e.Message);
            enabled = false;
            return;
        }
        if (wallSurface != null) wallSurface.position = HapticToolFollower.ToUnity(spec.Point) * follower.unitsPerMeter;
    }

    private void OnDisable()
    {
        if (wall_ == null) return;
        try { wall_.Remove(); } catch (HapticException) { }  // the session may have gone first
        wall_ = null;
    }
}
