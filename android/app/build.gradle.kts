// The APK around libbrume_android.so: a NativeActivity (android:hasCode="false"), whose
// native library cargo-ndk builds from the Rust workspace before every build.
plugins {
    id("com.android.application")
}

android {
    namespace = "org.brume.fog"
    compileSdk = 34

    defaultConfig {
        applicationId = "org.brume.fog"
        // 26: AHardwareBuffer, AImageReader_newWithUsage and
        // eglGetNativeClientBufferANDROID, which the camera path needs.
        minSdk = 26
        targetSdk = 34
        versionCode = 1
        versionName = "0.1.0"
        ndk {
            abiFilters += "arm64-v8a"
        }
    }

    buildTypes {
        release {
            isMinifyEnabled = false
            // Signed with the debug key so that `installRelease` works out of the box;
            // use a real key to publish.
            signingConfig = signingConfigs.getByName("debug")
        }
    }
}

// The repository's root, where the Cargo workspace is.
val repositoryRoot: File = rootProject.projectDir.parentFile

// cargo-ndk builds the Rust library for arm64-v8a, optimised, into src/main/jniLibs,
// which the Android plugin packages (for debug APKs too). Needs cargo-ndk, the aarch64-linux-android target and an
// NDK (ANDROID_NDK_HOME, or the SDK's ndk/ folder).
val cargoNdkBuild by tasks.registering(Exec::class) {
    group = "build"
    description = "Builds libbrume_android.so with cargo-ndk"
    workingDir = repositoryRoot
    commandLine(
        "cargo", "ndk",
        "-t", "arm64-v8a",
        "-o", "android/app/src/main/jniLibs",
        "build", "--release", "-p", "brume-android",
    )
}

tasks.named("preBuild") {
    dependsOn(cargoNdkBuild)
}
